#!/usr/bin/env bash
# nprfx synth --layout arnold|renderman|karma|vray|redshift|nuke: each renderer layout has
# exactly the channels its profile (nprfx/aov.h) names, with the synth layout's values bit for
# bit (motion in the convention's raw channels and signs, Nuke's depth as 1/z, object ids as a
# Cryptomatte layer whose rank-0 id is the MurmurHash3 float of the object's name), the header
# attributes (arnold/version, vrayInfo/*, cryptomatte/KEY/name|hash|conversion|manifest with KEY
# and the manifest computed here, independently of nprfx), and the engine reads the canonical
# AOVs of each plate through the profile it detects to the same pixels as the synth layout's.
# Pixels are compared bit for bit (-0 as 0) through uncompressed float EXR copies, read by the
# small python3 program below: no NumPy or OpenEXR bindings needed.
set -u
NPRFX=$1; SRC=$2; W=$3
rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
command -v oiiotool > /dev/null || { echo "FAIL: oiiotool (openimageio-tools) is needed"; exit 1; }
command -v python3 > /dev/null || { echo "FAIL: python3 is needed"; exit 1; }

cat > check.py <<'PY'
"""check.py channels EXR MAP | values EXR SYNTH_EXR MAP | header EXR LAYER SYNTH_EXR [ATTR=VALUE...]
| same DIR_A DIR_B FILE... | float NAME. MAP lines: "layout_channel kind synth_channel", kind copy, neg (x -1), inv (1/z,
0 for the 1e10 background), cryptoid, cryptocov, zero. Exit 1 with a message on a mismatch."""
import json, os, re, struct, subprocess, sys

def mm3(data):  # MurmurHash3_x86_32, seed 0
    M, c1, c2, h, n = 0xffffffff, 0xcc9e2d51, 0x1b873593, 0, len(data)
    rotl = lambda x, r: ((x << r) | (x >> (32 - r))) & M
    for i in range(0, n // 4 * 4, 4):
        k = struct.unpack('<I', data[i:i + 4])[0]
        k = rotl((k * c1) & M, 15) * c2 & M
        h = (rotl(h ^ k, 13) * 5 + 0xe6546b64) & M
    tail, k = data[n // 4 * 4:], 0
    for j, b in enumerate(tail):
        k |= b << (8 * j)
    if tail:
        h ^= rotl((k * c1) & M, 15) * c2 & M
    h ^= n
    h = ((h ^ (h >> 16)) * 0x85ebca6b) & M
    h = ((h ^ (h >> 13)) * 0xc2b2ae35) & M
    return h ^ (h >> 16)

def stored(h):  # the float's bits: exponent kept off 0 and 255
    return h ^ (1 << 23) if ((h >> 23) & 0xff) in (0, 255) else h

OBJECTS = {1: 'object "1"', 2: 'Objekt \u00fc/2', 3: 'object\\3'}
def object_name(i):
    return OBJECTS.get(i, 'object_%d' % i)
def object_bits(i):
    return stored(mm3(object_name(i).encode('utf-8')))

def f32(x):
    return struct.unpack('<f', struct.pack('<f', x))[0]
def bits(x):
    return struct.unpack('<I', struct.pack('<f', x))[0]

def flat(exr):  # an uncompressed float copy, kept for the next check of the same file
    return 'flat_' + exr.replace('/', '_')

def flatten(exrs):  # one oiiotool for all
    cmd = ['oiiotool']
    for exr in exrs:
        if not os.path.exists(flat(exr)):
            cmd += [exr, '-d', 'float', '--compression', 'none', '-o', flat(exr), '--pop']
    if len(cmd) > 1:
        subprocess.run(cmd, check=True, capture_output=True)

images = {}
def channels(exr):  # {name: float32 bits}
    if exr not in images:
        flatten([exr])
        d = open(flat(exr), 'rb').read()
        assert d[:4] == b'\x76\x2f\x31\x01' and not d[5] & 0x02, 'not a scanline EXR'
        pos, chans, box = 8, [], None
        while d[pos] != 0:  # attributes: name, type, size, value
            e = d.index(b'\0', pos); name = d[pos:e].decode(); pos = e + 1
            e = d.index(b'\0', pos); typ = d[pos:e].decode(); pos = e + 1
            size = struct.unpack('<i', d[pos:pos + 4])[0]; pos += 4
            val = d[pos:pos + size]; pos += size
            if typ == 'chlist':
                q = 0
                while val[q] != 0:
                    e = val.index(b'\0', q)
                    chans.append((val[q:e].decode(), struct.unpack('<i', val[e + 1:e + 5])[0]))
                    q = e + 17
            if name == 'dataWindow':
                box = struct.unpack('<4i', val)
        w, h = box[2] - box[0] + 1, box[3] - box[1] + 1
        assert all(t == 2 for _, t in chans), chans
        pos += 1 + 8 * h  # the end of the header, the line offsets (one line per block)
        out = {n: [] for n, _ in chans}
        for _ in range(h):
            pos += 8  # y, size
            for n, _ in chans:
                out[n] += struct.unpack('<%dI' % w, d[pos:pos + 4 * w]); pos += 4 * w
        images[exr] = out
    return images[exr]

def channel(exr, ch):
    return channels(exr)[ch]

def info(exr):
    return subprocess.run(['oiiotool', '--info', '-v', exr], check=True, capture_output=True,
                          text=True).stdout

def channel_list(exr):
    line = [l for l in info(exr).splitlines() if 'channel list:' in l][0]
    return [re.sub(r' \(.*\)$', '', c.strip()) for c in line.split(':', 1)[1].split(',')]

def read_map(path):
    return [l.split() for l in open(path) if l.strip()]

def fail(msg):
    print(msg)
    sys.exit(1)

cmd = sys.argv[1]
if cmd == 'float':
    print('%08x' % stored(mm3(sys.argv[2].encode('utf-8'))))
elif cmd == 'channels':
    have, want = channel_list(sys.argv[2]), [m[0] for m in read_map(sys.argv[3])]
    if sorted(have) != sorted(want):
        fail('channels %s, expected %s' % (sorted(have), sorted(want)))
elif cmd == 'values':
    exr, synth = sys.argv[2], sys.argv[3]
    ids = [int(struct.unpack('<f', struct.pack('<I', b))[0]) for b in channel(synth, 'id')]
    if not {1, 2, 3} <= set(ids):
        fail('the synth frame lacks ids 1-3: %s' % sorted(set(ids)))
    for name, kind, src in read_map(sys.argv[4]):
        got = channel(exr, name)
        s = [struct.unpack('<f', struct.pack('<I', b))[0] for b in channel(synth, src)]
        if kind == 'copy':
            want = [bits(v) for v in s]
        elif kind == 'neg':
            want = [bits(-v) for v in s]
        elif kind == 'inv':
            want = [0 if v >= f32(1e10) else bits(f32(1.0 / v)) for v in s]
        elif kind == 'cryptoid':
            want = [object_bits(int(v)) if v > 0 else 0 for v in s]
        elif kind == 'cryptocov':
            want = [bits(v) if i > 0 else 0 for v, i in zip(s, ids)]
        elif kind == 'zero':
            want = [0] * len(s)
        else:
            fail('bad kind ' + kind)
        zero = lambda b: 0 if b == 0x80000000 else b  # -0 is 0
        bad = [i for i in range(len(want)) if zero(got[i]) != zero(want[i])]
        if bad:
            i = bad[0]
            fail('%s (%s %s): %d pixels differ, first #%d: %08x, expected %08x' %
                 (name, kind, src, len(bad), i, got[i], want[i]))
        if kind in ('neg', 'inv', 'cryptoid') and len(set(want)) < 2:
            fail('%s: a constant channel proves nothing' % name)
elif cmd == 'flatten':  # flatten EXR...: the copies made at once
    flatten(sys.argv[2:])
elif cmd == 'same':  # same DIR_A DIR_B FILE...: the same channels and bits (-0 as 0)
    a, b = sys.argv[2], sys.argv[3]
    flatten([d + '/' + f for f in sys.argv[4:] for d in (a, b)])
    zero = lambda v: 0 if v == 0x80000000 else v
    for f in sys.argv[4:]:
        ca, cb = channels(a + '/' + f), channels(b + '/' + f)
        if sorted(ca) != sorted(cb):
            fail('%s: channels %s and %s' % (f, sorted(ca), sorted(cb)))
        for n in ca:
            bad = [i for i in range(len(ca[n])) if zero(ca[n][i]) != zero(cb[n][i])]
            if bad:
                fail('%s %s: %d pixels differ, first #%d: %08x, %08x' %
                     (f, n, len(bad), bad[0], ca[n][bad[0]], cb[n][bad[0]]))
elif cmd == 'header':
    exr, layer, synth = sys.argv[2], sys.argv[3], sys.argv[4]
    attrs = {}
    for l in info(exr).splitlines():
        m = re.match(r'^\s+(\S+): "(.*)"$', l)
        if m:
            attrs[m.group(1)] = m.group(2)
    key = '%08x' % mm3(layer.encode('utf-8'))
    key = key[:7]
    ids = sorted({int(struct.unpack('<f', struct.pack('<I', b))[0])
                  for b in channel(synth, 'id')} - {0})
    manifest = json.dumps({object_name(i): '%08x' % object_bits(i) for i in ids},
                          ensure_ascii=False, separators=(',', ':'))
    want = {'cryptomatte/%s/name' % key: layer, 'cryptomatte/%s/hash' % key: 'MurmurHash3_32',
            'cryptomatte/%s/conversion' % key: 'uint32_to_float32',
            'cryptomatte/%s/manifest' % key: manifest}
    for a in sys.argv[5:]:
        k, v = a.split('=', 1)
        want[k] = v
    for k, v in want.items():
        if attrs.get(k) != v:
            fail('%s: attribute %s is %r, expected %r' % (exr, k, attrs.get(k), v))
    if len(json.loads(manifest)) != len(ids):
        fail('manifest names collide')
PY

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
[ "$(python3 check.py float hello)" = 248bfa47 ] && pass || fail "check.py's MurmurHash3 of 'hello'"

"$NPRFX" synth orbit --size 96x64 --frames 1-2 -o synth/orbit.####.exr > /dev/null ||
  { echo "FAIL: synth layout"; exit 1; }
LAYOUTS="arnold renderman karma vray redshift nuke"
for L in $LAYOUTS; do
  out=$("$NPRFX" synth orbit --layout $L --size 96x64 --frames 1-2 -o $L/orbit.####.exr) ||
    { fail "synth --layout $L exited $?"; continue; }
  [ "$(printf '%s\n' "$out" | grep -c '^wrote ')" -eq 2 ] && pass || fail "$L: not two frames: $out"
done
python3 check.py flatten synth/orbit.000[12].exr */orbit.000[12].exr || fail "flattening"
for L in $LAYOUTS; do
  maps $L > $L.map
  python3 check.py channels $L/orbit.0001.exr $L.map > $L.log 2>&1 && pass ||
    { fail "$L channels:"; cat $L.log; }
  for f in 0001 0002; do
    python3 check.py values $L/orbit.$f.exr synth/orbit.$f.exr $L.map > $L.log 2>&1 && pass ||
      { fail "$L frame $f values:"; cat $L.log; }
  done
  layer=$(crypto_layer $L); attr=$(own_attr $L)
  if [ -n "$layer" ]; then
    for f in 0001 0002; do
      python3 check.py header $L/orbit.$f.exr "$layer" synth/orbit.$f.exr $attr > $L.log 2>&1 &&
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
python3 check.py values arnold/orbit.0001.exr synth/orbit.0001.exr wrong.map > wrong.log 2>&1 &&
  fail "a negated depth passed the values check" || pass
python3 check.py header arnold/orbit.0001.exr CryptoObject synth/orbit.0001.exr > wrong.log 2>&1 &&
  fail "the header check took the wrong layer's key" || pass

# --half: the layout's channels are half, the Cryptomatte layer stays float and exact.
"$NPRFX" synth orbit --layout redshift --half --size 96x64 --frames 2 -o half/orbit.####.exr \
  > /dev/null || fail "synth --layout redshift --half"
list=$(oiiotool --info -v half/orbit.0002.exr | grep 'channel list')
printf '%s\n' "$list" | grep -q 'R (half)' && printf '%s\n' "$list" | grep -q 'CryptoObject00.R (float)' &&
  ! printf '%s\n' "$list" | grep -q 'CryptoObject0[01].[RGBA] (half)' && pass ||
  fail "--half: channel types: $list"
grep -E '^CryptoObject' redshift.map > crypto.map
python3 check.py values half/orbit.0002.exr synth/orbit.0002.exr crypto.map > half.log 2>&1 &&
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
graph ${AOVS/depth /} > canon_nodepth.json
graph ${AOVS/ coverage/} > canon_nocoverage.json
graph coverage > canon_coverage.json
"$NPRFX" run canon.json --quiet --output-dir ref > ref.log 2>&1 || { fail "synth layout run:"; cat ref.log; }
for L in $LAYOUTS; do
  g=canon.json; [ $L = nuke ] && g=canon_nodepth.json # Nuke's depth is 1/z: compared above
  # KNOWN: a Karma plate is detected as Arnold's (below), whose coverage (A) and the generic
  # names miss Karma's C.A; its coverage is read with the profile given.
  [ $L = karma ] && g=canon_nocoverage.json
  "$NPRFX" run $g --quiet --output-dir run_$L --set plate.path=$L/orbit.####.exr > run_$L.log 2>&1 ||
    { fail "$L: reading its canonical AOVs:"; cat run_$L.log; continue; }
  [ $L = karma ] && { "$NPRFX" run canon_coverage.json --quiet --output-dir run_$L --aovs karma \
    --set plate.path=$L/orbit.####.exr > run_$L.log 2>&1 || { fail "karma coverage:"; cat run_$L.log; }; }
  files=
  for a in $AOVS; do
    [ $L = nuke ] && [ $a = depth ] && continue
    files="$files $a.0001.exr $a.0002.exr"
  done
  python3 check.py same ref/out run_$L/out $files > d.log 2>&1 && pass ||
    { fail "$L: its canonical AOVs differ from the synth layout's:"; cat d.log; }
done
# The comparison can fail: the engine reads Nuke's depth as stored, 1/z, not the synth depth.
if "$NPRFX" run canon.json --quiet --output-dir run_nukez --set plate.path=nuke/orbit.####.exr \
    > run_nukez.log 2>&1; then
  python3 check.py same ref/out run_nukez/out depth.0001.exr > d.log 2>&1 &&
    fail "Nuke's 1/z depth compared the same as the synth depth" || pass
else
  fail "nuke depth:"; cat run_nukez.log
fi
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
