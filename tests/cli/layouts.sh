#!/usr/bin/env bash
# nprfx synth --layout arnold|renderman|karma|vray|redshift|nuke: each renderer layout has
# exactly the channels its profile (nprfx/aov.h) names, with the synth layout's values bit for
# bit (motion in the convention's raw channels and signs, Nuke's depth as 1/z, object ids as a
# Cryptomatte layer whose rank-0 id is the MurmurHash3 float of the object's name), the header
# attributes (arnold/version, vrayInfo/*, cryptomatte/KEY/name|hash|conversion|manifest with KEY
# and the manifest computed here, independently of nprfx), and the engine reads the canonical
# AOVs of each plate through the profile it detects to the same pixels as the synth layout's.
# Pixels are compared bit for bit (-0 as 0) through uncompressed float EXR copies, read by the
# small python3 program tests/cli/exr_plates.py: no NumPy or OpenEXR bindings needed.
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
command -v oiiotool > /dev/null || { echo "FAIL: oiiotool (openimageio-tools) is needed"; exit 1; }
command -v python3 > /dev/null || { echo "FAIL: python3 is needed"; exit 1; }

check() { python3 "$SRC/tests/cli/exr_plates.py" "$@"; }

# The expected channels of each layout and what each holds.
maps() { # LAYOUT: "layout_channel kind synth_channel" lines
  local rgb=(R G B) xyz=(X Y Z) i
  layer3() { for i in 0 1 2; do echo "$1.${rgb[$i]} copy $2.${xyz[$i]}"; done; }
  albedo() { for i in 0 1 2; do echo "$1.${rgb[$i]} copy albedo.${rgb[$i]}"; done; }
  diffuse() { for i in 0 1 2; do echo "$1.${rgb[$i]} copy diffuse"; done; }
  uv() { echo "$1.R copy UV.U"; echo "$1.G copy UV.V"; }
  crypto() { echo "${1}00.R cryptoid id"; echo "${1}00.G cryptocov coverage"
             for c in 00.B 00.A 01.R 01.G 01.B 01.A; do echo "$1$c zero id"; done; }
  beauty() { echo "$1R copy R"; echo "$1G copy G"; echo "$1B copy B"; echo "$2 copy A"; }
  nextonly() { echo "$1.R copy motion_next.X"; echo "$1.G neg motion_next.Y"; }
  nprfxmotion() { echo "motion_prev.R copy motion_prev.X"; echo "motion_prev.G copy motion_prev.Y"
                  echo "motion_next.R copy motion_next.X"; echo "motion_next.G copy motion_next.Y"; }
  case $1 in
    arnold) beauty "" A; albedo diffuse_albedo; echo "Z copy Z"; layer3 N N; layer3 P P
            layer3 Pref Pref; uv uv; crypto crypto_object; nextonly motionvector ;;
    renderman) beauty Ci. a; albedo albedo; echo "z copy Z"; layer3 Nn N; layer3 P P
            layer3 __Pref Pref; uv st; echo "id copy id"; nprfxmotion ;;
    karma) beauty C. C.A; albedo albedo; echo "depth copy Z"; layer3 N N; layer3 P P
            layer3 Pref Pref; uv uv; crypto CryptoObject; nextonly motionvector ;;
    vray) beauty "" A; albedo VRayDiffuseFilter; diffuse VRayRawLighting; echo "depth copy Z"
            layer3 VRayNormals N; layer3 VRayWorldPosition P; layer3 Pref Pref; uv uv
            crypto CryptoObject; nprfxmotion ;;
    redshift) beauty "" A; albedo DiffuseFilter; diffuse DiffuseLightingRaw; echo "Z copy Z"
            layer3 N N; layer3 P P; layer3 Pref Pref; uv uv; crypto CryptoObject
            nextonly MotionVectors ;;
    nuke) beauty "" A; albedo albedo; echo "depth.Z inv Z"; layer3 N N; layer3 P P
            layer3 Pref Pref; uv uv; echo "id copy id"
            echo "backward.u copy motion_prev.X"; echo "backward.v neg motion_prev.Y"
            echo "forward.u copy motion_next.X"; echo "forward.v neg motion_next.Y" ;;
  esac
}
# The Cryptomatte layer and the renderer's own header attribute, where there are.
crypto_layer() { case $1 in arnold) echo crypto_object ;; karma|vray|redshift) echo CryptoObject ;; esac; }
own_attr() { case $1 in arnold) echo "arnold/version=7.3.1.0" ;; vray) echo "vrayInfo/camera=synth" ;; esac; }

# The python check itself can fail: a known MurmurHash3 value, and a wrong expectation refused.
[ "$(check float hello)" = 248bfa47 ] && pass || fail "exr_plates.py's MurmurHash3 of 'hello'"

"$NPRFX" synth orbit --size 96x64 --frames 1-2 -o synth/orbit.####.exr > /dev/null ||
  { echo "FAIL: synth layout"; exit 1; }
LAYOUTS="arnold renderman karma vray redshift nuke"
for L in $LAYOUTS; do
  out=$("$NPRFX" synth orbit --layout $L --size 96x64 --frames 1-2 -o $L/orbit.####.exr) ||
    { fail "synth --layout $L exited $?"; continue; }
  [ "$(printf '%s\n' "$out" | grep -c '^wrote ')" -eq 2 ] && pass || fail "$L: not two frames: $out"
done
check flatten synth/orbit.000[12].exr */orbit.000[12].exr || fail "flattening"
for L in $LAYOUTS; do
  maps $L > $L.map
  check channels $L/orbit.0001.exr $L.map > $L.log 2>&1 && pass ||
    { fail "$L channels:"; cat $L.log; }
  for f in 0001 0002; do
    check values $L/orbit.$f.exr synth/orbit.$f.exr $L.map > $L.log 2>&1 && pass ||
      { fail "$L frame $f values:"; cat $L.log; }
  done
  layer=$(crypto_layer $L); attr=$(own_attr $L)
  if [ -n "$layer" ]; then
    for f in 0001 0002; do
      check header $L/orbit.$f.exr "$layer" synth/orbit.$f.exr $attr > $L.log 2>&1 &&
        pass || { fail "$L frame $f header:"; cat $L.log; }
    done
  elif [ -n "$attr" ]; then
    oiiotool --info -v $L/orbit.0001.exr | grep -qF "${attr%%=*}: \"${attr#*=}\"" && pass ||
      fail "$L: no $attr"
  fi
  # No renderer's attribute where the renderer writes none, no Cryptomatte where it has no layer.
  hdr=$(oiiotool --info -v $L/orbit.0001.exr)
  for a in arnold/ vrayInfo/ cryptomatte/; do
    want=0
    case "$a" in arnold/) [ $L = arnold ] && want=1 ;; vrayInfo/) [ $L = vray ] && want=1 ;;
                 cryptomatte/) [ -n "$layer" ] && want=1 ;; esac
    got=0; printf '%s\n' "$hdr" | grep -q "^ *$a" && got=1
    [ $got = $want ] && pass || fail "$L: header attribute $a present: $got, expected $want"
  done
done

# A wrong expectation fails: the checks can fail.
sed 's/^Z copy Z$/Z neg Z/' arnold.map > wrong.map
check values arnold/orbit.0001.exr synth/orbit.0001.exr wrong.map > wrong.log 2>&1 &&
  fail "a negated depth passed the values check" || pass
check header arnold/orbit.0001.exr CryptoObject synth/orbit.0001.exr > wrong.log 2>&1 &&
  fail "the header check took the wrong layer's key" || pass

# --half: the layout's channels are half, the Cryptomatte layer stays float and exact.
"$NPRFX" synth orbit --layout redshift --half --size 96x64 --frames 2 -o half/orbit.####.exr \
  > /dev/null || fail "synth --layout redshift --half"
list=$(oiiotool --info -v half/orbit.0002.exr | grep 'channel list')
printf '%s\n' "$list" | grep -q 'R (half)' && printf '%s\n' "$list" | grep -q 'CryptoObject00.R (float)' &&
  ! printf '%s\n' "$list" | grep -q 'CryptoObject0[01].[RGBA] (half)' && pass ||
  fail "--half: channel types: $list"
grep -E '^CryptoObject' redshift.map > crypto.map
check values half/orbit.0002.exr synth/orbit.0002.exr crypto.map > half.log 2>&1 &&
  pass || { fail "--half Cryptomatte values:"; cat half.log; }

# The engine reads each plate's canonical AOVs through the profile it detects, to the synth
# layout's pixels (a zero-offset time-offset carries a selection to a write).
graph() { # AOV...
  printf '{"frames": "1-2", "nodes": {\n "plate": {"node": "read", "path": "synth/orbit.####.exr"}'
  for a in "$@"; do
    printf ',\n "t_%s": {"node": "time-offset", "inputs": {"image": "plate:%s"}, "params": {"offset": 0}}' "$a" "$a"
    printf ',\n "w_%s": {"node": "write", "inputs": {"image": "t_%s"}, "path": "out/%s.####.exr"}' "$a" "$a" "$a"
  done
  printf '}}\n'
}
AOVS="beauty albedo depth normal position rest uv coverage"
graph $AOVS > canon.json
"$NPRFX" run canon.json --quiet --output-dir ref > ref.log 2>&1 || { fail "synth layout run:"; cat ref.log; }
for L in $LAYOUTS; do
  "$NPRFX" run canon.json --quiet --output-dir run_$L --set plate.path=$L/orbit.####.exr > run_$L.log 2>&1 ||
    { fail "$L: reading its canonical AOVs:"; cat run_$L.log; continue; }
  files=
  for a in $AOVS; do
    [ $L = nuke ] && [ $a = depth ] && continue
    files="$files $a.0001.exr $a.0002.exr"
  done
  check same ref/out run_$L/out $files > d.log 2>&1 && pass ||
    { fail "$L: its canonical AOVs differ from the synth layout's:"; cat d.log; }
done
# Nuke's depth, stored as 1/z, reads back as 1/(1/z): within 1e-5 of the synth depth (1e10 where
# nothing is, infinite read back), where the layer "depth" holds the stored 1/z.
check close ref/out run_nuke/out 1e-5 0 1e-5 --far 1e9 depth.0001.exr depth.0002.exr > d.log 2>&1 &&
  pass || { fail "Nuke's depth read back:"; cat d.log; }
cat > nukez.json <<'G'
{"frames": "1", "nodes": {
 "plate": {"node": "read", "path": "nuke/orbit.####.exr"},
 "t": {"node": "time-offset", "inputs": {"image": "plate:depth.Z"}, "params": {"offset": 0}},
 "w": {"node": "write", "inputs": {"image": "t"}, "path": "out/depth.####.exr"}}}
G
"$NPRFX" run nukez.json --quiet --output-dir run_nukez > run_nukez.log 2>&1 || { fail "nuke depth.Z:"; cat run_nukez.log; }
check close ref/out run_nukez/out 1e-5 0 1e-5 --far 1e9 depth.0001.exr > d.log 2>&1 &&
  fail "Nuke's stored 1/z compared as the synth depth" || pass
# Nuke's vectors read back through the read node's "vectors": "nuke" are the synth motion.
cat > motion.json <<'G'
{"frames": "1-2", "nodes": {
 "n": {"node": "read", "path": "nuke/orbit.####.exr", "vectors": "nuke"},
 "s": {"node": "read", "path": "synth/orbit.####.exr"},
 "wn": {"node": "write", "inputs": {"image": "n:motion_prev.X,motion_prev.Y,motion_next.X,motion_next.Y"}, "path": "mn.####.exr"},
 "ws": {"node": "write", "inputs": {"image": "s:motion_prev.X,motion_prev.Y,motion_next.X,motion_next.Y"}, "path": "ms.####.exr"}}}
G
"$NPRFX" run motion.json --quiet --output-dir motion > motion.log 2>&1 || { fail "nuke vectors:"; cat motion.log; }
for f in 0001 0002; do
  "$NPRFX" diff motion/mn.$f.exr motion/ms.$f.exr --fail 0 --hardfail 0 > d.log 2>&1 && pass ||
    { fail "nuke vectors frame $f:"; cat d.log; }
done

# The profile the engine detects for each layout, from what the read announces: the fallback for
# diffuse light where the renderer has no pass, the Cryptomatte layer its ids are decoded from.
for la in arnold:arnold renderman:renderman karma:karma vray:vray redshift:redshift nuke:nuke; do
  L=${la%%:*}; want=${la#*:}
  a=diffuse_light; case $L in vray|redshift) a=id ;; esac
  cat > detect_$L.json <<G
{"frames": "1", "nodes": {
 "plate": {"node": "read", "path": "$L/orbit.####.exr"},
 "t": {"node": "time-offset", "inputs": {"image": "plate:$a"}, "params": {"offset": 0}},
 "w": {"node": "write", "inputs": {"image": "t"}, "path": "out/x.####.exr"}}}
G
  "$NPRFX" run detect_$L.json --output-dir detect_$L > detect_$L.log 2>&1
  grep -qF "plate 'plate' ($want" detect_$L.log && pass ||
    { fail "$L: expected detection as $want:"; cat detect_$L.log; }
done

# Usage: the layouts are listed; an unknown one (or the generic profile) is refused.
"$NPRFX" synth --help > help.txt
for L in synth blender $LAYOUTS; do grep -q "$L" help.txt && pass || fail "--help lacks $L"; done
grep -qxF "                   arnold|renderman|karma|vray|redshift|nuke (renderer layouts, below)" help.txt &&
  pass || fail "--help: layout list"
for bad in generic maya; do
  "$NPRFX" synth orbit --layout $bad -o bad.exr > bad.log 2>&1
  st=$?
  [ $st -eq 2 ] && grep -qF -e "--layout must be one of synth, blender, arnold, renderman, karma, vray, redshift, nuke, not '$bad'" bad.log && [ ! -e bad.exr ] &&
    pass || { fail "--layout $bad: status $st"; cat bad.log; }
done
echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
