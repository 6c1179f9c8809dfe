#!/usr/bin/env bash
# Canonical AOVs through renderer profiles (nprfx/aov.h, docs/design.md §2.4): a graph that names
# what it means ("plate:depth", "plate:normal", "plate:id", "plate:coverage") renders the same
# pixels on a Blender-named plate and on the same plate under Arnold's names, whether the profile
# is detected or given (--aovs, "aovs"); descriptors' AOV hints find Arnold's names too; a plate
# without an AOV fails, writing nothing, naming the AOV, the profile and the names it looked for.
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W"
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }

"$NPRFX" synth orbit --layout blender --size 96x64 --frames 1-2 -o bl/orbit.####.exr > /dev/null ||
  { echo "FAIL: synth"; exit 1; }
# The same numbers under Arnold's AOV names (Arnold Developer Guide, "AOVs").
VL=ViewLayer
mkdir -p ar nonormal
for f in 0001 0002; do
  oiiotool bl/orbit.$f.exr --ch "R=$VL.Combined.R,G=$VL.Combined.G,B=$VL.Combined.B,A=$VL.Combined.A,Z=$VL.Depth.Z,N.R=$VL.Normal.X,N.G=$VL.Normal.Y,N.B=$VL.Normal.Z,P.R=$VL.Position.X,P.G=$VL.Position.Y,P.B=$VL.Position.Z,ID=$VL.IndexOB.X,diffuse_albedo.R=$VL.DiffCol.R,diffuse_albedo.G=$VL.DiffCol.G,diffuse_albedo.B=$VL.DiffCol.B" \
    -o ar/orbit.$f.exr > /dev/null 2>&1 || { echo "FAIL: oiiotool"; exit 1; }
  # and a plate without normals
  oiiotool ar/orbit.$f.exr --ch "R,G,B,A,Z,ID" -o nonormal/orbit.$f.exr > /dev/null 2>&1
done

cat > canon.json <<'G'
{"frames": "1-2", "nodes": {
 "plate": {"node": "read", "path": "bl/orbit.####.exr"},
 "ink": {"node": "lines", "inputs": {"id": "plate:id", "coverage": "plate:coverage",
         "depth": "plate:depth", "normal": "plate:normal"}, "params": {"width": 1.5}},
 "w": {"node": "write", "inputs": {"image": "ink"}, "path": "out/ink.####.exr"}}}
G
cat > hints.json <<'G'
{"frames": "1-2", "nodes": {
 "plate": {"node": "read", "path": "bl/orbit.####.exr"},
 "ink": {"node": "lines", "inputs": {"id": "plate", "coverage": "plate:coverage", "depth": "plate",
         "normal": "plate"}, "params": {"width": 1.5}},
 "w": {"node": "write", "inputs": {"image": "ink"}, "path": "out/ink.####.exr"}}}
G
same() { # DIR_A DIR_B WHAT: every EXR equal at zero tolerance
  local n=0
  for f in 0001 0002; do
    n=$((n+1))
    "$NPRFX" diff "$1/ink.$f.exr" "$2/ink.$f.exr" --fail 0 > d.txt 2>&1 || { fail "$3: frame $f differs:"; cat d.txt; return; }
  done
  pass
}
run() { # OUTDIR GRAPH [args...]
  local out=$1 graph=$2; shift 2
  "$NPRFX" run "$graph" --quiet --output-dir "$out" "$@" > "$out.log" 2>&1 || { fail "run $graph $*:"; cat "$out.log"; }
}
run blender canon.json
run arnold canon.json --set plate.path=ar/orbit.####.exr
run arnold_given canon.json --set plate.path=ar/orbit.####.exr --aovs arnold
run arnold_set canon.json --set plate.path=ar/orbit.####.exr --set plate.aovs=arnold
run hints_blender hints.json
run hints_arnold hints.json --set plate.path=ar/orbit.####.exr
same blender/out arnold/out "canonical names, Blender and Arnold plates (detected)"
same blender/out arnold_given/out "canonical names, --aovs arnold"
same blender/out arnold_set/out "canonical names, plate.aovs=arnold"
same blender/out hints_blender/out "descriptor hints against canonical names on Blender plates"
same blender/out hints_arnold/out "descriptor hints on Arnold plates"

# A plate without an AOV an input can do without: the lines draw without normals, said once.
"$NPRFX" run canon.json --output-dir nonormal_run --set plate.path=nonormal/orbit.####.exr \
  --aovs arnold > nonormal_run.log 2>&1
st=$?
[ $st -eq 0 ] && [ -s nonormal_run/out/ink.0002.exr ] &&
  [ "$(grep -c "warning: plate 'plate' (arnold profile) has no normal: the inputs that take it are left unconnected" nonormal_run.log)" = 1 ] &&
  pass || { fail "optional normal: status $st"; cat nonormal_run.log; }
# A plate without an AOV an input needs: refused before a frame is written, with the AOV, the
# profile and its names.
cat > needs.json <<'G'
{"frames": "1-2", "nodes": {
 "plate": {"node": "read", "path": "nonormal/orbit.####.exr", "aovs": "arnold"},
 "t": {"node": "time-offset", "inputs": {"image": "plate:normal"}},
 "w": {"node": "write", "inputs": {"image": "t"}, "path": "out/n.####.exr"}}}
G
"$NPRFX" run needs.json --quiet --output-dir missing > missing.log 2>&1
st=$?
msg="node 't': input 'image': plate 'plate' has no normal: its arnold profile looks for N"
[ $st -ne 0 ] && grep -qF "$msg" missing.log && [ ! -e missing/out/n.0001.exr ] && pass ||
  { fail "missing normal: status $st, expected '$msg':"; cat missing.log; }
# A profile that is none.
"$NPRFX" run canon.json --quiet --output-dir bad --aovs maya > bad.log 2>&1
grep -qF "node 'plate': aovs 'maya' is not one of: auto, generic, blender, arnold, renderman, karma, vray, redshift, nuke" bad.log &&
  pass || { fail "bad profile:"; cat bad.log; }
# A profile given wrongly is the user's word: Blender plates read as V-Ray have no V-Ray names.
# The lines do without the id, coverage and depth, each said once; without the normal too they
# would have nothing to draw from, so the run fails before a frame is written, in V-Ray's terms.
"$NPRFX" run canon.json --output-dir wrong --aovs vray > wrong.log 2>&1
st=$?
[ $st -ne 0 ] && [ "$(grep -c "warning: plate 'plate' (vray profile) has no id" wrong.log)" = 1 ] &&
  [ "$(grep -c "warning: plate 'plate' (vray profile) has no depth" wrong.log)" = 1 ] &&
  grep -qF "plate 'plate' has no normal: its vray profile looks for VRayNormals;" wrong.log &&
  [ ! -e wrong/out/ink.0001.exr ] && pass || { fail "wrong profile: status $st"; cat wrong.log; }
# A plate with only beauty and depth (an Arnold render's R,G,B,A and Z): toon.json runs unedited
# but for plate.path, each missing AOV said once with what stands in (optical flow for the
# vectors), and every frame written.
mkdir -p bd
"$NPRFX" synth orbit --layout arnold --size 96x64 --frames 1-3 -o arl/orbit.####.exr > /dev/null || fail "synth arnold"
for f in 1 2 3; do oiiotool arl/orbit.000$f.exr --ch R,G,B,A,Z -o bd/orbit.000$f.exr || fail "oiiotool"; done
"$NPRFX" run "$SRC/samples/graphs/toon.json" --set plate.path="$W/bd/orbit.####.exr" --shot 1-3 \
  --output-dir bdout > bd.log 2>&1
st=$?
ok=1
for w in "has no id: the inputs that take it are left unconnected" \
  "has no albedo: beauty stands in" "has no motion vectors: optical flow on its beauty stands in" \
  "has no normal: the inputs that take it are left unconnected"; do
  [ "$(grep -c "warning: plate 'plate' (arnold profile) $w" bd.log)" = 1 ] || ok=0
done
[ $st -eq 0 ] && [ $ok = 1 ] && [ -s bdout/out/toon/toon.0003.exr ] && pass ||
  { fail "beauty and depth only: status $st"; cat bd.log; }
# nprfx info --aovs: the profile, the channels each AOV comes from (decoded where the read
# decodes), what stands in for a missing one, and whether each sample style runs on the plate.
"$NPRFX" info --aovs arl/orbit.0001.exr > info.log 2>&1
grep -q "arl/orbit.0001.exr: arnold profile" info.log && grep -Eq "^  depth +Z$" info.log &&
  grep -Eq "^  id +aov.id +\(object ids from Cryptomatte layer crypto_object\)" info.log &&
  grep -Eq "^  motion_prev +motion_prev.X motion_prev.Y +\(the renderer writes one motion vector" info.log &&
  grep -Eq "^  diffuse_light +R G B A +\(beauty stands in" info.log &&
  grep -Eq "^  toon +runs as is$" info.log && grep -Eq "^  stipple_2d +not tried" info.log && pass ||
  { fail "info --aovs on an Arnold plate"; cat info.log; }
"$NPRFX" info --aovs bd/orbit.0001.exr --styles "$SRC/samples/graphs" > infobd.log 2>&1
grep -Eq "^  normal +missing: the profile looks for N$" infobd.log &&
  grep -Eq "^  motion_prev +optical flow on the beauty" infobd.log &&
  grep -Eq "^  rest +aov.position.X aov.position.Y aov.position.Z +\(position stands in" infobd.log &&
  ! grep -q "does not run" infobd.log && [ "$(grep -Ec "^  [a-z_0-9]+ +runs" infobd.log)" = 22 ] &&
  grep -Eq "^  toon +runs with fallbacks: .*albedo" infobd.log && pass ||
  { fail "info --aovs on a beauty and depth plate"; cat infobd.log; }
# A studio's own names through a mapping file: the Arnold plate with its normal, id and depth
# renamed reads, with "aovs" naming the file (relative to the graph) or --aovs (relative to here),
# to the Blender plate's pixels; the AOVs it does not map keep Arnold's names.
mkdir -p studio
for f in 0001 0002; do
  oiiotool ar/orbit.$f.exr --ch "R,G,B,A,Zdepth=Z,nrm.R=N.R,nrm.G=N.G,nrm.B=N.B,P.R,P.G,P.B,objectId=ID" \
    -o studio/orbit.$f.exr > /dev/null 2>&1 || fail "oiiotool studio"
done
cat > studio.json <<'M'
{"profile": "arnold", "aovs": {"normal": "nrm", "id": "objectId|oid", "depth": "Zdepth", "albedo": null},
 "depth": "z"}
M
mkdir -p maps && cp studio.json maps/studio.json
sed 's|"path": "bl/orbit.####.exr"|"path": "studio/orbit.####.exr", "aovs": "studio.json"|' canon.json > canon_studio.json
run studio_file canon_studio.json
run studio_cli canon.json --set plate.path=studio/orbit.####.exr --aovs maps/studio.json
same blender/out studio_file/out "a mapping file named by the read"
same blender/out studio_cli/out "a mapping file named by --aovs"
"$NPRFX" run canon.json --quiet --output-dir studio_none --set plate.path=studio/orbit.####.exr \
  --aovs arnold > studio_none.log 2>&1
grep -qF "warning: plate 'plate' (arnold profile) has no normal" studio_none.log && pass ||
  { fail "the renamed plate without its mapping:"; cat studio_none.log; }
# What the mapping says is not written is missing, in its terms; a bad mapping names file and key.
cat > needs_map.json <<'G'
{"frames": "1", "nodes": {
 "plate": {"node": "read", "path": "studio/orbit.####.exr", "aovs": "nonormal.json"},
 "t": {"node": "time-offset", "inputs": {"image": "plate:normal"}},
 "w": {"node": "write", "inputs": {"image": "t"}, "path": "out/a.####.exr"}}}
G
echo '{"profile": "arnold", "aovs": {"normal": null}}' > nonormal.json
"$NPRFX" run needs_map.json --quiet --output-dir nm > nm.log 2>&1
grep -qF "plate 'plate' has no normal: its nonormal.json profile looks for no fixed channel name" nm.log &&
  [ ! -e nm/out/a.0001.exr ] && pass || { fail "an AOV the mapping leaves out:"; cat nm.log; }
for bad in '{"aov": {}}#aov: is not one of profile, aovs, vectors, depth' \
  '{"aovs": {"zdepth": "Z"}}#zdepth: is not a canonical AOV (beauty, albedo' \
  '{"profile": "maya"}#profile: must be one of generic, blender' \
  '{"aovs": {"depth": 1}}#depth: must be channel names' \
  '{"vectors": "maya"}#vectors: must be one of none, blender' '[1]#must be a JSON object' \
  '{"aovs": }#malformed JSON near line 1'; do
  echo "${bad%%#*}" > badmap.json
  "$NPRFX" run canon.json --quiet --output-dir badmap --aovs badmap.json > badmap.log 2>&1
  st=$?
  [ $st -ne 0 ] && grep -qF "badmap.json" badmap.log && grep -qF "${bad#*#}" badmap.log &&
    [ ! -e badmap/out/ink.0001.exr ] && pass || { fail "mapping ${bad%%#*}: status $st"; cat badmap.log; }
done
"$NPRFX" run canon.json --quiet --output-dir nomap --aovs nowhere.json > nomap.log 2>&1
grep -qF "cannot open AOV mapping" nomap.log && grep -qF "nowhere.json" nomap.log && pass ||
  { fail "a missing mapping file:"; cat nomap.log; }

# "colorspace": "auto": an 8-bit PNG is read as sRGB (as "srgb" reads it), a float EXR as it is.
cat > cs.json <<'G'
{"frames": "1", "nodes": {
 "plate": {"node": "read", "path": "in.####.EXT", "colorspace": "auto"},
 "t": {"node": "time-offset", "inputs": {"image": "plate:beauty.RGB"}, "params": {"offset": 0}},
 "w": {"node": "write", "inputs": {"image": "t"}, "path": "out/cs.####.exr"}}}
G
oiiotool arl/orbit.0001.exr --ch R,G,B -o in.0001.exr > /dev/null 2>&1 &&
  oiiotool in.0001.exr -d uint8 -o in.0001.png > /dev/null 2>&1 || fail "oiiotool"
sed 's/EXT/png/' cs.json > cs_png.json; sed 's/EXT/exr/' cs.json > cs_exr.json
for x in png exr; do
  for cs in auto srgb linear; do
    "$NPRFX" run cs_$x.json --quiet --output-dir cs_${x}_$cs --set plate.colorspace=$cs > cs.log 2>&1 ||
      { fail "colorspace $cs on $x:"; cat cs.log; }
  done
done
same_cs() { "$NPRFX" diff "$1" "$2" --fail "$3" > d.txt 2>&1; }
same_cs cs_png_auto/out/cs.0001.exr cs_png_srgb/out/cs.0001.exr 0 &&
  ! same_cs cs_png_auto/out/cs.0001.exr cs_png_linear/out/cs.0001.exr 0.01 &&
  same_cs cs_exr_auto/out/cs.0001.exr cs_exr_linear/out/cs.0001.exr 0 &&
  same_cs in.0001.exr cs_exr_auto/out/cs.0001.exr 0 && pass ||
  { fail "colorspace auto: PNG as sRGB, EXR as it is:"; cat d.txt; }
echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
