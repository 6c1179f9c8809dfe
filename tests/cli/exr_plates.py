"""EXR plates and renders compared bit for bit without NumPy or OpenEXR bindings (oiiotool makes
uncompressed float copies, read here). Commands:
  channels EXR MAP | values EXR SYNTH_EXR MAP | header EXR LAYER SYNTH_EXR [ATTR=VALUE...]
  | same DIR_A DIR_B FILE... | close DIR_A DIR_B T PERCENT HARD [--far F] FILE... | float NAME
  | blender-as CHANGES DST_DIR SRC... | flatten EXR...
MAP lines: "layout_channel kind synth_channel", kind copy, neg (x -1), inv (1/z, 0 for the 1e10
background), cryptoid, cryptocov, zero. Exit 1 with a message on a mismatch."""
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

def layout(d):  # an uncompressed float scanline EXR's channels, width, height, first line
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
    assert struct.unpack('<q', d[pos + 1:pos + 9])[0] == pos + 1 + 8 * h, 'one line per block'
    return [n for n, _ in chans], w, h, pos + 1 + 8 * h  # past the header and the line offsets

def offset(start, w, nch, y, c):  # where channel c of line y starts
    return start + y * (8 + 4 * w * nch) + 8 + 4 * w * c

images = {}
def channels(exr):  # {name: float32 bits}
    if exr not in images:
        flatten([exr])
        d = open(flat(exr), 'rb').read()
        names, w, h, start = layout(d)
        out = {n: [] for n in names}
        for y in range(h):
            for c, n in enumerate(names):
                p = offset(start, w, len(names), y, c)
                out[n] += struct.unpack('<%dI' % w, d[p:p + 4 * w])
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
elif cmd == 'close':
    # close DIR_A DIR_B T PERCENT HARD [--far F] FILE...: in each file a pixel's error is its
    # largest absolute channel difference (nprfx diff's); at most PERCENT % of pixels over T, none
    # over HARD. With --far, two values both at least F (a depth's background: 1e10, inf) are
    # equal. Prints each file's share over T and largest error.
    a, b, t, percent, hard = sys.argv[2], sys.argv[3], *map(float, sys.argv[4:7])
    files, far = sys.argv[7:], float('inf')
    if files[:1] == ['--far']:
        far, files = float(files[1]), files[2:]
    flatten([d + '/' + f for f in files for d in (a, b)])
    value = lambda v: struct.unpack('<f', struct.pack('<I', v))[0]
    errors = []
    for f in files:
        ca, cb = channels(a + '/' + f), channels(b + '/' + f)
        if sorted(ca) != sorted(cb):
            fail('%s: channels %s and %s' % (f, sorted(ca), sorted(cb)))
        err = [0.0] * len(next(iter(ca.values())))
        for n in ca:
            for i, (x, y) in enumerate(zip(ca[n], cb[n])):
                if x != y and not (value(x) >= far and value(y) >= far):
                    e = abs(value(x) - value(y))
                    err[i] = max(err[i], e if e == e else float('inf'))
        over = 100.0 * sum(e > t for e in err) / len(err)
        print('%s: %.2f%% over %g, largest %g' % (f, over, t, max(err)))
        if over > percent or max(err) > hard:
            errors.append(f)
    if errors:
        fail('beyond %g%% over %g or any over %g: %s' % (percent, t, hard, ' '.join(errors)))
elif cmd == 'blender-as':
    # blender-as CHANGES DST_DIR SRC...: Blender-layout plates carrying the numbers another
    # layout's plates give the engine, as uncompressed float EXRs. CHANGES, comma separated:
    # nodiffuse (no diffuse light pass), cryptoids (IndexOB as the ids the read decodes from a
    # Cryptomatte layer: the stored float of the object name's hash, all 32 bits, where there is
    # coverage), prevfromnext (the vector to the previous frame as the opposite of the one to the
    # next: Vector.XY = Vector.ZW), inversedepth (depth through Nuke's 1/z and back, infinite
    # where there is nothing).
    changes, dst_dir, srcs = sys.argv[2].split(','), sys.argv[3], sys.argv[4:]
    keep = [c for c in channel_list(srcs[0]) if not ('nodiffuse' in changes and '.DiffDir.' in c)]
    os.makedirs(dst_dir, exist_ok=True)
    cmd = ['oiiotool']
    for src in srcs:
        cmd += [src, '--ch', ','.join(keep), '-d', 'float', '--compression', 'none', '-o',
                os.path.join(dst_dir, os.path.basename(src)), '--pop']
    subprocess.run(cmd, check=True, capture_output=True)
    for src in srcs:
        dst = os.path.join(dst_dir, os.path.basename(src))
        d = bytearray(open(dst, 'rb').read())
        names, w, h, start = layout(d)
        col = lambda n, y: offset(start, w, len(names), y, names.index('ViewLayer.' + n))
        get = lambda n, y: list(struct.unpack('<%df' % w, d[col(n, y):col(n, y) + 4 * w]))
        def put(n, y, v):
            d[col(n, y):col(n, y) + 4 * w] = struct.pack('<%df' % w, *v)
        for y in range(h):
            if 'cryptoids' in changes:
                a = get('Combined.A', y)
                ids = get('IndexOB.X', y)
                put('IndexOB.X', y, [struct.unpack('<f', struct.pack('<I', object_bits(int(i))))[0]
                                     if i > 0 and c > 0 else 0.0 for i, c in zip(ids, a)])
            if 'prevfromnext' in changes:
                put('Vector.X', y, get('Vector.Z', y))
                put('Vector.Y', y, get('Vector.W', y))
            if 'inversedepth' in changes:
                put('Depth.Z', y, [float('inf') if z >= f32(1e10) else f32(1.0 / f32(1.0 / z))
                                   for z in get('Depth.Z', y)])
        open(dst, 'wb').write(d)
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
