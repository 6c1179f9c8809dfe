"""The Python module (python/nprfx_module.c): the node list is the runner's, from the
descriptors; errors are nprfx.Error with the runner's words; with NumPy, a render on arrays of
any strides gives the same pixels, and two threads render at once (the GIL is released).
usage: python3 test_module.py NPRFX (PYTHONPATH: the build's python/ folder)"""
import subprocess
import sys
import threading

import nprfx

runner = sys.argv[1]
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print('FAIL: ' + what)


# The node list: every node `nprfx list` shows, with the descriptors' params and help.
listed = {line.split()[0] for line in subprocess.run([runner, 'list'], capture_output=True,
                                                     text=True, check=True).stdout.splitlines()
          if line.strip()}
nodes = nprfx.nodes()
# (read, write and synth are the runner's graph nodes, not descriptors)
check(listed - {'read', 'write', 'synth'} == set(nodes),
      'nodes() and `nprfx list` differ: %s' % sorted(listed ^ set(nodes)))
check('tone' in nodes and nodes['tone'].params['range'].help, "tone.range has no help")
help_text = subprocess.run([runner, 'help', 'blend'], capture_output=True, text=True).stdout
for name, p in nodes['blend'].params.items():
    check(name in help_text, 'blend.%s is not in `nprfx help blend`' % name)
check(nodes['blend'].params['opacity'].max == 1.0, 'blend.opacity max is not 1')

# Errors: the runner's words for a param out of range.
try:
    nprfx.render('blend', inputs={'base': memoryview(bytearray(16)).cast('f', (2, 2))},
                 params={'opacity': 1.5})
    check(False, 'blend.opacity 1.5 was taken')
except nprfx.Error as e:
    check(str(e) == 'blend.opacity: 1.5 is outside the range [0, 1]', 'message: %s' % e)
try:
    nprfx.render('threshold-map', inputs={'tone': b'abcd'})
    check(False, 'bytes were taken as an image')
except nprfx.Error as e:
    check("input 'tone'" in str(e) and 'float32' in str(e), 'message: %s' % e)
try:
    nprfx.render('no-such-node')
    check(False, 'an unknown node rendered')
except nprfx.Error as e:
    check("no node 'no-such-node'" in str(e), 'message: %s' % e)

try:
    import numpy as np
except ImportError:
    np = None
    print('SKIP (renders): NumPy is not installed (Debian: python3-numpy)')

if np is not None:
    h, w = 72, 96
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    tone = (x / w).astype(np.float32)
    pattern = (0.5 + 0.5 * np.sin(x * 0.3 + y * 0.2)).astype(np.float32)
    a = nprfx.render('threshold-map', inputs={'tone': tone, 'pattern': pattern},
                     params={'mode': 'builtin'}, threads=2)
    check(a.dtype == np.float32 and a.shape[:2] == (h, w), 'shape %s' % (a.shape,))
    # any strides: a transposed array's transpose, a channel of an interleaved array
    inter = np.stack([pattern, tone], axis=2)
    b = nprfx.render('threshold-map', inputs={'tone': np.ascontiguousarray(tone.T).T,
                                              'pattern': inter[:, :, 0]},
                     params={'mode': 'builtin'}, threads=1)
    check(np.array_equal(a, b), 'strides or threads change the pixels')
    # the GIL is released: two threads render at once, each the same as alone
    out = [None, None]

    def work(i):
        out[i] = nprfx.render('threshold-map', inputs={'tone': tone, 'pattern': pattern},
                              params={'mode': 'builtin'}, threads=1)
    ts = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    check(all(o is not None and np.array_equal(o, a) for o in out), 'threaded renders differ')

if failures:
    sys.exit(1)
print('python module: passed')
