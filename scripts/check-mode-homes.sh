#!/usr/bin/env bash
# The "one home per mode" rule (docs/architecture.md): every job mode is named
# in code by at most 3 files of server/ and api/ (its own file(s), the
# registration, at most one more). A mode is "named in code" by its JSON name
# as a string ("palette") or an identifier made from it (palette_mode,
# PaletteParams, PaletteMode); plain words in comments and messages are not
# counted, since "solid" and "surface" are also the geometry's words.
#   scripts/check-mode-homes.sh [REPO_DIR]    exits 1 when a mode breaks the rule
set -euo pipefail
repo="${1:-$(cd "$(dirname "$0")/.." && pwd)}"
cd "$repo"
modes=$(python3 -c 'import json,sys; print("\n".join(json.load(open("proto-schemas/job-params.schema.json"))["properties"]["mode"]["enum"]))')
status=0
for mode in $modes; do
  stem=${mode//+/_and_}
  camel=$(echo "$stem" | sed -E 's/(^|_)([a-z])/\U\2/g')
  files=$(grep -rlE --include='*.cpp' --include='*.h' -e "\"${mode//+/\\+}\"" -e "\b${stem}_mode\b" -e "\b${camel}(Params|Mode)\b" server api | sort || true)
  count=$(echo -n "$files" | grep -c . || true)
  printf '%-14s %d  %s\n' "$mode" "$count" "$(echo $files)"
  if (( count > 3 )); then status=1; fi
done
exit $status
