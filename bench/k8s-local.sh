#!/usr/bin/env bash
# The Kubernetes recipe run here without a cluster (no control plane can be installed on these
# machines): examples/farm/k8s-indexed-job.yaml is validated offline (PyPI's
# kubernetes-validate, strict, for every version from the one the manifest states to the
# newest the package knows, and shown to fail two versions below), the image is built by
# examples/farm/container/build-image.sh, and the Job's own pod command and environment, read
# from the YAML, run for every completion index in podman containers sharing one fresh
# volume (a folder mounted at the manifest's mountPath, at most `parallelism` at once). The
# frames are then compared byte for byte with one `kardia render --frames` run.
#
#   bench/k8s-local.sh [SCENE] [WORKDIR]
#
# SCENE (default scenes/heartbeat.scene) must make as many frames as the manifest's
# completions; it is copied to where the manifest's SCENE points on the volume. WORKDIR
# (default: a fresh temporary folder) receives volume/ and sequential/. KARDIA: the binary
# (default: a release build). K8S_VENV: the virtual environment for kubernetes-validate
# (default .venv-k8s, made if missing). Exits 77, saying so loudly, when podman cannot start
# a container on this machine.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD
scene=$(realpath "${1:-scenes/heartbeat.scene}")
work=${2:-$(mktemp -d)}
mkdir -p "$work"
work=$(realpath "$work")
manifest=$repo/examples/farm/k8s-indexed-job.yaml
venv=${K8S_VENV:-$repo/.venv-k8s}
if [[ -z "${KARDIA:-}" ]]; then
  cargo build --release --quiet
  KARDIA=$repo/target/release/kardia
fi
export KARDIA

echo "== offline validation (kubernetes-validate --strict)"
if ! "$venv/bin/python" -c "import kubernetes_validate, yaml" >/dev/null 2>&1; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q "kubernetes-validate==1.37.0"
fi
floor=$(grep -oE 'Kubernetes 1\.[0-9]+ or newer' "$manifest" | head -1 | grep -oE '1\.[0-9]+')
newest=$("$venv/bin/python" -c '
import os, re, kubernetes_validate
d = os.path.join(os.path.dirname(kubernetes_validate.__file__), "kubernetes-json-schema")
print(max((int(m.group(1)) for n in os.listdir(d) if (m := re.match(r"v1\.(\d+)\.0-local$", n))), default=0))')
for ((minor = ${floor#1.}; minor <= newest; minor++)); do
  "$venv/bin/kubernetes-validate" --strict --quiet -k "1.$minor.0" "$manifest"
done
echo "valid for Kubernetes $floor to 1.$newest (the stated minimum: $floor)"
below=$((${floor#1.} - 2))
if "$venv/bin/kubernetes-validate" --strict --quiet -k "1.$below.0" "$manifest" >/dev/null 2>&1; then
  echo "the manifest also validates for 1.$below: its stated minimum $floor is not the floor" >&2
  exit 1
fi
echo "rejected for 1.$below, as expected"

echo "== image"
conf=$work/containers.conf
printf '[containers]\ndefault_ulimits = []\npids_limit = 0\n' >"$conf"
export CONTAINERS_CONF=$conf
export PODMAN="podman --runtime runc"
tag=localhost/kardia-k8s-local:$$
if ! command -v podman >/dev/null 2>&1; then
  echo "SKIPPED: podman is not installed (apt-get install podman runc uidmap slirp4netns)" >&2
  exit 77
fi
examples/farm/container/build-image.sh "$tag"
cleanup() { $PODMAN rmi --force "$tag" >/dev/null 2>&1 || true; }
trap cleanup EXIT
if ! why=$($PODMAN run --rm --network none "$tag" /bin/sh -c 'kardia --version' 2>&1); then
  echo "SKIPPED: this machine cannot start a container with podman: $why" >&2
  exit 77
fi
echo "a container starts: $why"

echo "== the Job's pods, one container per completion index, one fresh volume"
rm -rf "$work/volume" "$work/sequential"
mkdir -p "$work/volume" "$work/sequential"
"$venv/bin/python" - "$manifest" "$work/volume" "$scene" "$tag" <<'PY'
import concurrent.futures, os, shlex, shutil, subprocess, sys, time, yaml

manifest, volume, scene, image = sys.argv[1:5]
docs = [d for d in yaml.safe_load_all(open(manifest)) if d]
job = next(d for d in docs if d["kind"] == "Job")
claims = {d["metadata"]["name"]: d for d in docs if d["kind"] == "PersistentVolumeClaim"}
spec = job["spec"]
pod = spec["template"]["spec"]
(container,) = pod["containers"]
(mount,) = container["volumeMounts"]
(vol,) = [v for v in pod["volumes"] if v["name"] == mount["name"]]
claim = claims[vol["persistentVolumeClaim"]["claimName"]]
assert "ReadWriteMany" in claim["spec"]["accessModes"], "the shared volume must be ReadWriteMany"
env = {e["name"]: e["value"] for e in container.get("env", [])}
# The scene goes where the pods read it: SCENE on the volume.
inside = env["SCENE"]
assert inside.startswith(mount["mountPath"] + "/"), inside
target = os.path.join(volume, os.path.relpath(inside, mount["mountPath"]))
os.makedirs(os.path.dirname(target), exist_ok=True)
shutil.copyfile(scene, target)
frames = int(subprocess.check_output([os.environ["KARDIA"], "render", scene, "--print-frame-count"]))
count = spec["completions"]
assert frames == count, f"the scene makes {frames} frames, the Job has {count} completions"
podman = shlex.split(os.environ["PODMAN"])

def run(index):
    argv = podman + ["run", "--rm", "--network", "none", "-v", f"{volume}:{mount['mountPath']}"]
    for name, value in list(env.items()) + [("JOB_COMPLETION_INDEX", str(index))]:
        argv += ["-e", f"{name}={value}"]
    argv += [image] + container["command"] + container.get("args", [])
    done = subprocess.run(argv, capture_output=True, text=True)
    return index, done.returncode, done.stderr

print(f"command: {shlex.join(container['command'] + container.get('args', []))}")
print(f"env: {' '.join(f'{k}={v}' for k, v in env.items())} JOB_COMPLETION_INDEX=0..{count - 1}")
start = time.monotonic()
failed = 0
with concurrent.futures.ThreadPoolExecutor(max_workers=spec.get("parallelism", 1)) as pool:
    for index, code, err in pool.map(run, range(count)):
        if code != 0:
            failed += 1
            print(f"index {index}: exit {code}\n{err}", file=sys.stderr)
print(f"{count} pods ({spec.get('parallelism', 1)} at a time): {count - failed} succeeded, "
      f"{failed} failed, {time.monotonic() - start:.1f} s")
sys.exit(1 if failed else 0)
PY

echo "== compare with one sequential --frames run"
out=$work/volume/out
n=$(ls "$out" | wc -l)
"$KARDIA" render "$scene" --frames 0..$((n - 1)) --quiet -o "$work/sequential/frame_####.png"
for f in "$work"/sequential/frame_*.png; do
  cmp "$f" "$out/$(basename "$f")"
done
echo "$n frames from the pods == the sequential run (byte for byte)"
