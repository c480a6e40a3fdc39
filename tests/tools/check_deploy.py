#!/usr/bin/env python3
"""Checks the deployment files against the code, since no container engine
runs here (docker-compose reads the compose file, with no engine): the Dockerfile builds with the scripts CI runs and its runtime
stage installs every library the binary links (ldd); compose, Kubernetes and
systemd use only settings `voxd serve --help` lists, probe the real routes,
and give running jobs more time to stop than voxd's own shutdown grace.

check_deploy.py SOURCE_DIR VOXD_BINARY
"""
import os
import re
import subprocess
import sys
import tempfile

import yaml

source, binary = sys.argv[1], sys.argv[2]
problems = []


def check(ok, message):
    if not ok:
        problems.append(message)


def read(rel):
    return open(os.path.join(source, rel)).read()


help_text = subprocess.run([binary, "serve", "--help"], capture_output=True, text=True, check=True).stdout
known_env = set(re.findall(r"\((VOXD_[A-Z_]+)\)", help_text))
known_flags = set(re.findall(r"(--[a-z-]+) \(VOXD_", help_text))
check(len(known_env) >= 8, "serve --help lists too few settings")
grace_default = int(re.search(r"--shutdown-grace.*\[default: (\d+)\]", help_text).group(1))

# --- Dockerfile -------------------------------------------------------------
docker = read("Dockerfile")
lines = [l.strip() for l in docker.replace("\\\n", " ").splitlines() if l.strip() and not l.strip().startswith("#")]
stages = [l for l in lines if l.startswith("FROM ")]
check(len(stages) >= 2, "Dockerfile: needs a build stage and a runtime stage")
check(all(re.match(r"FROM debian:12(-slim)?\b", s) for s in stages), "Dockerfile: every stage must be Debian 12")
build_runs = " ".join(l for l in lines[: lines.index(stages[1])] if l.startswith("RUN "))
check("./scripts/install-deps.sh" in build_runs and "./scripts/build.sh" in build_runs,
      "Dockerfile: the build stage must run scripts/install-deps.sh and scripts/build.sh, as CI does")
ci = read(".ci/run") + read("scripts/test.sh")
check("scripts/test.sh" in read(".ci/run") and "scripts/build.sh" in read("scripts/test.sh"),
      "CI must run scripts/test.sh, which builds with scripts/build.sh")
runtime = lines[lines.index(stages[1]):]
check(any("install-deps.sh --runtime" in l for l in runtime), "Dockerfile: the runtime stage must install with --runtime")
copied = [l for l in runtime if l.startswith("COPY --from=build")]
check(copied and copied[0].split()[2] == "/src/build/server/voxd", "Dockerfile: copy build/server/voxd from the build stage")
check(os.path.relpath(binary, source).endswith("server/voxd"), "the binary checked is not build/server/voxd")
users = [l.split()[1] for l in runtime if l.startswith("USER ")]
check(users and users[-1].split(":")[0] not in ("root", "0"), "Dockerfile: must run as a non-root user")
health = [l for l in runtime if l.startswith("HEALTHCHECK")]
check(health and "/healthz" in health[0], "Dockerfile: HEALTHCHECK must probe /healthz")
env = dict(re.findall(r"(VOXD_[A-Z_]+)=(\S+)", " ".join(l for l in runtime if l.startswith("ENV "))))
for name in env:
    check(name in known_env, f"Dockerfile: {name} is not a voxd setting")
expose = [l.split()[1] for l in runtime if l.startswith("EXPOSE ")]
check(expose == [env.get("VOXD_PORT")], "Dockerfile: EXPOSE must match VOXD_PORT")
check(env.get("VOXD_HOST") == "0.0.0.0", "Dockerfile: listen on all interfaces inside the container")
check(f"127.0.0.1:{env.get('VOXD_PORT')}/healthz" in health[0] if health else False, "Dockerfile: HEALTHCHECK port")

# The runtime packages cover every shared library the binary needs.
listed = set(subprocess.run([os.path.join(source, "scripts/install-deps.sh"), "--print-runtime"],
                            capture_output=True, text=True, check=True).stdout.split())


def dependency_closure(packages):
    """The listed packages and everything apt installs with them (Depends and
    Pre-Depends of the installed packages, recursively)."""
    seen, todo = set(), list(packages)
    while todo:
        p = todo.pop()
        if p in seen:
            continue
        seen.add(p)
        r = subprocess.run(["dpkg-query", "-W", "-f=${Depends}, ${Pre-Depends}", p], capture_output=True, text=True)
        for alternative in r.stdout.split(","):
            name = alternative.split("|")[0].strip().split(" ")[0].split(":")[0]
            if name:
                todo.append(name)
    return seen


installed_with_runtime = dependency_closure(listed)
ldd = subprocess.run(["ldd", binary], capture_output=True, text=True, check=True).stdout
for lib in re.findall(r"=> (/\S+)", ldd):
    real = os.path.realpath(lib)
    owner = None
    for candidate in (real, lib, "/usr" + lib if not lib.startswith("/usr") else lib[4:]):
        r = subprocess.run(["dpkg", "-S", candidate], capture_output=True, text=True)
        if r.returncode == 0:
            owner = r.stdout.split(":")[0]
            break
    if "asan" in lib or "ubsan" in lib:
        continue  # sanitizer builds link their runtimes; the image is a Release build
    check(owner is not None, f"no Debian package owns {lib}")
    if owner:
        check(owner in installed_with_runtime, f"runtime stage misses {owner} (for {os.path.basename(lib)}): add it to install-deps.sh")

# --- compose -----------------------------------------------------------------
# Docker's own reading of the file (Debian's docker-compose: the Compose
# file schema, interpolation, and the build context, with no engine).
config = subprocess.run(["docker-compose", "-f", os.path.join(source, "deploy/compose.yaml"), "config", "-q"],
                        capture_output=True, text=True)
check(config.returncode == 0 and not config.stderr.strip(),
      "docker-compose config: " + (config.stderr + config.stdout).strip())
compose = yaml.safe_load(read("deploy/compose.yaml"))
svc = compose["services"]["voxd"]
check(svc["build"]["dockerfile"] == "Dockerfile" and os.path.normpath(os.path.join(source, "deploy", svc["build"]["context"])) == os.path.normpath(source),
      "compose: must build the repository's Dockerfile")
for name in svc.get("environment", {}):
    check(name in known_env, f"compose: {name} is not a voxd setting")
check(any("/readyz" in part or "/healthz" in part for part in svc["healthcheck"]["test"]), "compose: healthcheck must probe voxd")
grace = int(svc.get("environment", {}).get("VOXD_SHUTDOWN_GRACE", grace_default))
check(int(svc["stop_grace_period"].rstrip("s")) > grace, "compose: stop_grace_period must exceed VOXD_SHUTDOWN_GRACE")
redis_url = svc.get("environment", {}).get("VOXD_REDIS_URL", "")
if redis_url:
    # Scale-out: the replicas share the Redis the file runs, which keeps an
    # append-only file and never evicts; clients reach one endpoint.
    redis_svc = compose["services"].get(redis_url.split("//")[1].split(":")[0])
    check(redis_svc is not None, "compose: VOXD_REDIS_URL must name the Redis service of the file")
    command = " ".join(redis_svc.get("command", [])) if redis_svc else ""
    check("--appendonly yes" in command, "compose: Redis must run with --appendonly yes (accepted jobs survive a restart)")
    check("--maxmemory-policy noeviction" in command, "compose: Redis must not evict results (noeviction)")
    check(any(v.endswith(":/data") for v in redis_svc.get("volumes", [])), "compose: Redis's data must be a volume")
    check(svc.get("deploy", {}).get("replicas", 1) >= 2, "compose: several voxd replicas")
    check("ports" not in svc, "compose: replicas are reached through the endpoint, not published one by one")
    endpoint = compose["services"].get("endpoint", {})
    check(endpoint.get("ports") and "nginx.conf" in " ".join(endpoint.get("volumes", [])), "compose: an endpoint in front")
    nginx = read("deploy/nginx.conf")
    check("server voxd:8080" in nginx, "compose: the endpoint must proxy to the voxd service")
    # Replicas come and go: the endpoint looks their name up again, with a
    # resolver and a shared zone (nginx 1.27.3+), not once at start.
    check(re.search(r"server voxd:8080 [^;]*\bresolve\b", nginx) and re.search(r"^\s*resolver \S+", nginx, re.M)
          and re.search(r"^\s*zone \S+", nginx, re.M), "compose: the endpoint must re-resolve the replicas (resolver, zone, resolve)")
    version = re.match(r"nginx:(\d+)\.(\d+)", endpoint.get("image", ""))
    check(version and (int(version.group(1)), int(version.group(2))) >= (1, 27), "compose: `resolve` in an upstream needs nginx 1.27.3+")
else:
    check(any(str(v).endswith(":/var/lib/voxd") for v in svc["volumes"]), "compose: the data dir must be a volume")


def check_kubernetes(path, shared):
    docs = [d for d in yaml.safe_load_all(read(path)) if d]
    kinds = {}
    for d in docs:
        kinds.setdefault(d["kind"], d)
    check({"Deployment", "Service"} <= set(kinds), f"{path}: needs a Deployment and a Service")
    deployment = kinds["Deployment"]
    pod = deployment["spec"]["template"]["spec"]
    container = pod["containers"][0]
    kenv = {e["name"]: e.get("value") for e in container.get("env", [])}
    for name in kenv:
        check(name in known_env, f"{path}: {name} is not a voxd setting")
    port = container["ports"][0]
    check(str(port["containerPort"]) == kenv.get("VOXD_PORT"), f"{path}: containerPort must match VOXD_PORT")
    check(container["readinessProbe"]["httpGet"]["path"] == "/readyz", f"{path}: readiness probe must be /readyz")
    check(container["livenessProbe"]["httpGet"]["path"] == "/healthz", f"{path}: liveness probe must be /healthz")
    check({"cpu", "memory"} <= set(container["resources"]["limits"]), f"{path}: cpu and memory limits")
    check(pod["terminationGracePeriodSeconds"] > int(kenv.get("VOXD_SHUTDOWN_GRACE", grace_default)),
          f"{path}: terminationGracePeriodSeconds must exceed VOXD_SHUTDOWN_GRACE")
    check(pod["securityContext"].get("runAsNonRoot") is True, f"{path}: runAsNonRoot")
    mem_limit = container["resources"]["limits"]["memory"]
    units = {"Gi": 1 << 30, "Mi": 1 << 20}
    limit_bytes = int(mem_limit[:-2]) * units[mem_limit[-2:]]
    check(int(kenv.get("VOXD_MAX_JOB_MEMORY", 0)) < limit_bytes, f"{path}: VOXD_MAX_JOB_MEMORY must be under the memory limit")
    services = [d for d in docs if d["kind"] == "Service" and d["spec"]["selector"] == deployment["spec"]["selector"]["matchLabels"]]
    check(len(services) == 1, f"{path}: one Service selects the voxd pods")
    if services:
        check(services[0]["spec"]["ports"][0]["targetPort"] in (port.get("name"), port["containerPort"]),
              f"{path}: Service must target the container port")
    volumes = pod.get("volumes", [])
    if not shared:
        check(deployment["spec"]["replicas"] == 1 and deployment["spec"]["strategy"]["type"] == "Recreate",
              f"{path}: the embedded store is one replica's disk (1 replica, Recreate)")
        return
    check("VOXD_REDIS_URL" in kenv, f"{path}: the replicas need VOXD_REDIS_URL")
    check(not any("persistentVolumeClaim" in v for v in volumes), f"{path}: replicas on Redis need no shared volume")
    check(deployment["spec"]["replicas"] >= 2, f"{path}: several replicas")
    check("HorizontalPodAutoscaler" in kinds and kinds["HorizontalPodAutoscaler"]["spec"]["scaleTargetRef"]["name"]
          == deployment["metadata"]["name"], f"{path}: a HorizontalPodAutoscaler for the Deployment")
    redis = kinds.get("StatefulSet")
    check(redis is not None and redis["spec"].get("volumeClaimTemplates"), f"{path}: Redis as a StatefulSet with a persistent volume")
    config = " ".join(str(d.get("data", "")) for d in docs if d["kind"] == "ConfigMap")
    check("appendonly yes" in config and "maxmemory-policy noeviction" in config,
          f"{path}: Redis with appendonly and noeviction")
    host = kenv["VOXD_REDIS_URL"].split("//")[1].split(":")[0]
    check(any(d["kind"] == "Service" and d["metadata"]["name"] == host for d in docs), f"{path}: VOXD_REDIS_URL must name the Redis Service")


# --- Kubernetes --------------------------------------------------------------
check_kubernetes("deploy/kubernetes/voxd.yaml", shared=False)
check_kubernetes("deploy/kubernetes/voxd-redis.yaml", shared=True)
docs = [d for f in ("voxd.yaml", "voxd-redis.yaml") for d in yaml.safe_load_all(read("deploy/kubernetes/" + f)) if d]
# The two variants can live in one namespace: no object name or pod label in common.
names = [(d["kind"], d["metadata"]["name"]) for d in docs]
check(len(names) == len(set(names)), f"kubernetes: both variants define {sorted(n for n in names if names.count(n) > 1)}")
apps = [frozenset(d["spec"]["selector"]["matchLabels"].items()) for d in docs if d["kind"] == "Deployment"]
check(len(apps) == len(set(apps)), "kubernetes: the two Deployments select the same pods")
for d in docs:
    for c in d.get("spec", {}).get("template", {}).get("spec", {}).get("containers", []):
        if c["image"].endswith(":latest") or ":" not in c["image"]:
            check(c.get("imagePullPolicy") == "IfNotPresent" or "/" in c["image"].split(":")[0],
                  f"kubernetes: {c['image']} is a locally built image: imagePullPolicy IfNotPresent (\":latest\" is pulled)")

# --- the Docker build context ----------------------------------------------------
ignored = [l.strip() for l in read(".dockerignore").splitlines() if l.strip() and not l.startswith("#")]
check("web/node_modules" in ignored, ".dockerignore: web/node_modules (hundreds of MB; the build runs npm ci itself)")

# --- systemd -----------------------------------------------------------------
unit = read("deploy/systemd/voxd.service")
exec_start = re.search(r"^ExecStart=(.*)$", unit, re.M).group(1).split()
check(exec_start[:2] == ["/usr/local/bin/voxd", "serve"], "systemd: ExecStart must run voxd serve")
for flag in (a.split("=")[0] for a in exec_start[2:] if a.startswith("--")):
    check(flag in known_flags, f"systemd: {flag} is not a voxd serve flag")
for name in re.findall(r"(VOXD_[A-Z_]+)=", unit):
    check(name in known_env, f"systemd: {name} is not a voxd setting")
check(re.search(r"^KillSignal=SIGTERM$", unit, re.M), "systemd: stop with SIGTERM")
stop = int(re.search(r"^TimeoutStopSec=(\d+)$", unit, re.M).group(1))
unit_grace = int(re.search(r"VOXD_SHUTDOWN_GRACE=(\d+)", unit).group(1))
check(stop > unit_grace, "systemd: TimeoutStopSec must exceed VOXD_SHUTDOWN_GRACE")
check("DynamicUser=yes" in unit or re.search(r"^User=(?!root)", unit, re.M), "systemd: must not run as root")
# systemd's own check of the unit (with ExecStart pointed at this build's
# binary, which is not installed here): unknown keys and bad values are errors.
with tempfile.TemporaryDirectory() as tmp:
    verify_path = os.path.join(tmp, "voxd.service")
    with open(verify_path, "w") as f:
        f.write(unit.replace("/usr/local/bin/voxd", os.path.abspath(binary)))
    verify = subprocess.run(["systemd-analyze", "verify", verify_path], capture_output=True, text=True)
    check(verify.returncode == 0 and not verify.stderr.strip() and not verify.stdout.strip(),
          "systemd-analyze verify: " + (verify.stderr + verify.stdout).strip())

if problems:
    print("deploy files:\n  " + "\n  ".join(problems))
    sys.exit(1)
print(f"deploy files: Dockerfile ({len(stages)} stages), compose, kubernetes ({len(docs)} objects), systemd consistent with voxd")
