#!/usr/bin/env bash
# The repository stands alone: no tracked file refers to the developers'
# folder beside the checkout (its meshes are for trying things by hand; a
# user's clone has no such folder). Tests take their meshes from code
# (tests/support/test_parts.h) or from a Debian package that
# scripts/install-deps.sh installs.
#   scripts/check-stands-alone.sh [REPO]     exits 1 and lists the lines found
set -euo pipefail
repo="${1:-$(dirname "$0")/..}"
cd "$repo"
pattern='\.\./shared\b|shared/meshes|SHARED_MESHES'
if ! git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  echo "check-stands-alone: $repo is not a git checkout" >&2
  exit 2
fi
# Every file git tracks, and new ones it does not ignore; not this one.
if found=$(git grep --untracked -n -I -E "$pattern" -- . ':!scripts/check-stands-alone.sh'); then
  echo "check-stands-alone: these tracked lines refer to a folder outside the repository:" >&2
  echo "$found" >&2
  exit 1
fi
echo "check-stands-alone: $(git ls-files | wc -l) tracked files, none refers to a folder outside the repository"
