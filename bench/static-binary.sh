#!/usr/bin/env bash
# A kardia binary for older nodes: what the usual build needs of glibc (its newest versioned
# symbol, by objdump -T), then a static build for x86_64-unknown-linux-musl that needs no C
# library at all. The static binary is checked to be static, renders a small animated scene
# whose frames are compared with the usual build's (musl's libm may round sin, exp or pow
# differently, so they are compared byte for byte and the count of differing frames is
# printed, not assumed), and, where podman can start a container, is run alone in an empty
# image (FROM scratch, no libraries) to render a frame there.
#
#   bench/static-binary.sh [SCENE]      (default scenes/heartbeat.scene, frames at 160x120)
#
# Needs the musl target (rustup target add x86_64-unknown-linux-musl; made here if rustup can)
# and prints where the static binary is. KARDIA: the usual build to compare with (default: a
# release build).
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-scenes/heartbeat.scene}
target=x86_64-unknown-linux-musl
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

if [[ -z "${KARDIA:-}" ]]; then
  cargo build --release --quiet
  KARDIA=target/release/kardia
fi
glibc=$KARDIA
floor=$(objdump -T "$glibc" | grep -oE 'GLIBC_[0-9]+(\.[0-9]+)*' | sort -uV | tail -1)
echo "== the usual build: $glibc"
echo "newest glibc symbol version it needs: $floor"
objdump -T "$glibc" | grep -E "$floor\b" | awk '{print "  " $NF}' | sort -u

echo "== static build for $target"
if ! rustup target list --installed 2>/dev/null | grep -qx "$target"; then
  rustup target add "$target"
fi
cargo build --release --quiet --target "$target"
static=target/$target/release/kardia
echo "$static: $(file -b "$static" | cut -d, -f1-2,5)"
if ldd "$static" >/dev/null 2>&1 && ! ldd "$static" 2>&1 | grep -q "statically linked"; then
  echo "not static:" >&2
  ldd "$static" >&2
  exit 1
fi
echo "ldd: $(ldd "$static" 2>&1 | tr -d '\t')"

echo "== the same frames from both builds"
frames=$("$static" render "$scene" --print-frame-count)
last=$((frames - 1))
"$glibc" render "$scene" --width 160 --height 120 --spp 2 --frames 0..$last --quiet -o "$work/glibc_####.png"
"$static" render "$scene" --width 160 --height 120 --spp 2 --frames 0..$last --quiet -o "$work/musl_####.png"
differ=0
for f in "$work"/glibc_*.png; do
  cmp -s "$f" "${f/glibc_/musl_}" || differ=$((differ + 1))
done
echo "$frames frames rendered by each build; $differ differ byte for byte"

echo "== the static binary alone in an empty image"
if command -v podman >/dev/null 2>&1; then
  printf '[containers]\ndefault_ulimits = []\npids_limit = 0\n' >"$work/containers.conf"
  export CONTAINERS_CONF=$work/containers.conf
  mkdir -p "$work/ctx" "$work/out"
  cp "$static" "$work/ctx/kardia"
  printf 'FROM scratch\nCOPY kardia /kardia\n' >"$work/ctx/Containerfile"
  tag=localhost/kardia-static:$$
  podman --runtime runc build --quiet --tag "$tag" "$work/ctx" >/dev/null
  cp "$scene" "$work/out/scene"
  if podman --runtime runc run --rm --network none -v "$work/out:/w" "$tag" /kardia render /w/scene \
    --frame 0 --width 160 --height 120 --spp 2 --quiet -o /w/frame_####.png; then
    cmp "$work/out/frame_0000.png" "$work/musl_0000.png"
    echo "frame 0 rendered in an image holding nothing but the binary == the same binary outside"
  else
    echo "SKIPPED: podman could not start a container here" >&2
  fi
  podman rmi --force "$tag" >/dev/null 2>&1 || true
else
  echo "SKIPPED: podman is not installed" >&2
fi
echo "static binary: $static ($(du -h "$static" | cut -f1))"
