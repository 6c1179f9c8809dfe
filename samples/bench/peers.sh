#!/bin/sh
# Side by side on this machine: nprfx's nodes that have an oiiotool equivalent, on the same
# 1920x1080 RGB float frames' worth of work and the same number of threads (the figures of
# docs/performance.md). oiiotool's time is its own --runstats figure for the operation alone:
# the inputs are read beforehand (-i:now=1) and the operation is repeated ten times.
#
#   multiply:  nprfx blend mode=multiply          vs  oiiotool --mul
#   warp:      nprfx warp (bilinear, by offsets)  vs  oiiotool --st_warp:filter=triangle (and its
#              default filter), by an ST map one pixel off the identity
#
# usage: samples/bench/peers.sh [NPRFX] [THREADS]     (defaults: build/nprfx, 2)
set -eu
NPRFX=${1:-build/nprfx}
T=${2:-2}
REPEAT=10
command -v oiiotool > /dev/null || { echo "peers.sh: needs oiiotool (Debian: openimageio-tools)" >&2; exit 2; }
[ -x "$NPRFX" ] || { echo "peers.sh: no nprfx at $NPRFX (build first, or pass its path)" >&2; exit 2; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

oiiotool --pattern noise:type=uniform:min=0:max=1 1920x1080 3 -d float -o "$dir/a.exr"
oiiotool --pattern noise:type=uniform:min=0:max=1:seed=2 1920x1080 3 -d float -o "$dir/b.exr"
# s, t at pixel centres, moved by about a third of a pixel so that every lookup interpolates
oiiotool --pattern fill:topleft=0.0002,0.0003:topright=1.0002,0.0003:bottomleft=0.0002,1.0003:bottomright=1.0002,1.0003 \
  1920x1080 2 -d float -o "$dir/st.exr"

# ms per operation from oiiotool's runtime statistics line for OP ("  -mul : 1.23")
oiio_ms() { # OP ARGS...
  op=$1
  shift
  oiiotool --threads "$T" --runstats "$@" -o "$dir/out.exr" 2>&1 |
    awk -v op="-$op" -v n="$REPEAT" '$1 == op { printf "%.1f", $3 * 1000 / n }'
}
repeat() { # ARGS... repeated REPEAT times
  out=""
  i=0
  while [ $i -lt $REPEAT ]; do out="$out $*"; i=$((i + 1)); done
  echo "$out"
}
# nprfx bench's mean ms per frame
nprfx_ms() {
  "$NPRFX" bench "$@" --threads "$T" --frames $REPEAT 2>&1 |
    sed -n 's/.* frames\{0,1\}, [0-9]* threads\{0,1\}: \([0-9.]*\) ms\/frame (best \([0-9.]*\);.*/\1 (best \2)/p'
}

mul_oiio=$(oiio_ms mul -i:now=1 "$dir/a.exr" $(repeat -i:now=1 "$dir/b.exr" --mul))
mul_nprfx=$(nprfx_ms blend --set mode=multiply --connect base=R,G,B --connect layer=R,G,B)
warp_tri=$(oiio_ms st_warp -i:now=1 "$dir/a.exr" $(repeat -i:now=1 "$dir/st.exr" --st_warp:filter=triangle))
warp_def=$(oiio_ms st_warp -i:now=1 "$dir/a.exr" $(repeat -i:now=1 "$dir/st.exr" --st_warp))
warp_nprfx=$(nprfx_ms warp --connect image=R,G,B)

echo "1920x1080, 3 channels, $T threads, ms per frame"
printf '%-34s %-22s %s\n' "operation" "nprfx" "oiiotool $(oiiotool --version 2>/dev/null | head -1)"
printf '%-34s %-22s %s\n' "multiply two images" "$mul_nprfx" "$mul_oiio (--mul)"
printf '%-34s %-22s %s\n' "warp, bilinear" "$warp_nprfx" "$warp_tri (--st_warp:filter=triangle)"
printf '%-34s %-22s %s\n' "" "" "$warp_def (--st_warp, its default filter)"
