#!/usr/bin/env bash
# Builds the container image that examples/farm/k8s-indexed-job.yaml runs, from this
# repository, with podman and without pulling anything: an image FROM scratch (Containerfile)
# holding the kardia binary at /usr/local/bin/kardia, /bin/sh and /bin/mkdir for the pod's
# command, and every shared library these load (as ldd lists them on this machine; a static
# binary brings none).
#
#   examples/farm/container/build-image.sh [TAG]        (default: kardia:latest)
#
# KARDIA: the binary to put in (default: `cargo build --release`, target/release/kardia; a
# static one from bench/static-binary.sh works too). Its debug information is stripped.
# PODMAN: the podman command (default: podman). Where the sandbox forbids setting resource
# limits (a container inside a container), point CONTAINERS_CONF at a file holding
#   [containers]
#   default_ulimits = []
#   pids_limit = 0
# and use PODMAN="podman --runtime runc". Then push the image to the cluster's registry:
#   podman tag kardia:latest registry.example/kardia:latest && podman push registry.example/kardia:latest
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
tag=${1:-kardia:latest}
podman_cmd=${PODMAN:-podman}
if [[ -z "${KARDIA:-}" ]]; then
  (cd "$here/../../.." && cargo build --release --quiet)
  KARDIA=$here/../../../target/release/kardia
fi
context=$(mktemp -d)
trap 'rm -rf "$context"' EXIT
root=$context/root
mkdir -p "$root/usr/local/bin" "$root/bin"
# Copies $1 into the image at $2 with the libraries it loads, each at its own path.
add() {
  local libs
  install -m 755 "$1" "$root$2"
  libs=$(ldd "$1" 2>/dev/null | grep -o '/[^ ]*' || true)
  for lib in $libs; do
    mkdir -p "$root$(dirname "$lib")"
    cp -L "$lib" "$root$lib"
  done
}
add "$KARDIA" /usr/local/bin/kardia
strip --strip-debug "$root/usr/local/bin/kardia" 2>/dev/null || true
add "$(command -v sh)" /bin/sh
add "$(command -v mkdir)" /bin/mkdir
cp "$here/Containerfile" "$context/Containerfile"
# shellcheck disable=SC2086
$podman_cmd build --quiet --tag "$tag" "$context" >/dev/null
echo "built $tag: $(du -sh "$root" | cut -f1) (kardia, sh, mkdir and their libraries)"
