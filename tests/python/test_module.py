"""The Python module (python/): the node list is the runner's, from the descriptors; errors are
nprfx.Error with the runner's words; a render on arrays of any strides gives the same pixels,
Python code runs while a node computes (the GIL is released), and 1,000 renders leak no
reference and no memory.
usage: python3 test_module.py NPRFX [WORK_DIR] (PYTHONPATH: the build's python/ folder)"""
import os
import subprocess
import sys
import threading
import time

from checks import check, finish

import nprfx

runner = sys.argv[1]


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

import numpy as np  # noqa: E402 (checks.py has made sure it is there)

h, w = 72, 96
y, x = np.mgrid[0:h, 0:w].astype(np.float32)
tone = (x / w).astype(np.float32)
pattern = (0.5 + 0.5 * np.sin(x * 0.3 + y * 0.2)).astype(np.float32)
a = nprfx.render('threshold-map', inputs={'tone': tone, 'pattern': pattern},
                 params={'mode': 'builtin'}, threads=2)
check(a.dtype == np.float32 and a.shape[:2] == (h, w), 'shape %s' % (a.shape,))
# bad arrays: a message naming the node, the input and what is wrong
def error_of(**kw):
    try:
        nprfx.render('threshold-map', **kw)
    except nprfx.Error as e:
        return str(e)
    return 'no error'
e = error_of(inputs={'tone': tone.astype(np.float64), 'pattern': pattern})
check("threshold-map input 'tone'" in e and 'float32' in e, 'float64: %s' % e)
e = error_of(inputs={'tone': np.stack([tone, tone], axis=2), 'pattern': pattern})
check("input 'tone': it has 2 channels; the input takes 1 channel" in e, 'channels: %s' % e)
e = error_of(inputs={'tone': tone[:-1], 'pattern': pattern})
check("(W x H); the other inputs are 96 x 71" in e, "size: %s" % e)
e = error_of(inputs={'tonality': tone, 'pattern': pattern})
check("threshold-map has no input 'tonality'" in e, 'name: %s' % e)
e = error_of(inputs={'tone': tone, 'pattern': pattern}, params={'modes': 1})
check("threshold-map has no param 'modes'" in e, 'param: %s' % e)
# any strides: a transposed array's transpose, a channel of an interleaved array
inter = np.stack([pattern, tone], axis=2)
b = nprfx.render('threshold-map', inputs={'tone': np.ascontiguousarray(tone.T).T,
                                          'pattern': inter[:, :, 0]},
                 params={'mode': 'builtin'}, threads=1)
check(np.array_equal(a, b), 'strides or threads change the pixels')
# the GIL is released: another thread's Python code runs while a render computes. It notes
# the time every 1,000 turns; with the GIL held through the render none of those times could
# fall inside it (10 ms from either end, clear of the switches around the call).
big = np.ascontiguousarray(np.tile(pattern, (8, 8)))
stamps = []
finished = threading.Event()

def count():
    k = 0
    while not finished.is_set():
        k += 1
        if k % 1000 == 0:
            stamps.append(time.perf_counter())
slow = {'anchor': np.stack([big, big.T.copy().T], axis=2), 'depth': np.ones_like(big)}
n = nprfx.Node('gabor-splat', params={'radius': 24, 'anchor_space': 'uv'}, threads=1)
t = threading.Thread(target=count)
t.start()
time.sleep(0.02)
start = time.perf_counter()
n.render(1, slow)
end = time.perf_counter()
finished.set()
t.join()
inside = [x for x in stamps if start + 0.01 < x < end - 0.01]
check(end - start > 0.03, 'the render took %.3f s: too short to tell' % (end - start))
check(len(inside) > 3, 'Python ran %d times during %.3f s of render' % (len(inside),
                                                                        end - start))

# no leak: 1,000 renders keep every reference count and the resident size
def rss_mb():
    with open('/proc/self/statm') as f:
        return int(f.read().split()[1]) * os.sysconf('SC_PAGE_SIZE') / 2**20
inputs = {'tone': tone, 'pattern': pattern}
params = {'mode': 'builtin', 'sigma': 4}
for _ in range(50):
    nprfx.render('threshold-map', inputs=inputs, params=params, threads=1)
refs = [sys.getrefcount(o) for o in (tone, pattern, inputs, params, 'builtin')]
rss = rss_mb()
n = nprfx.Node('time-offset', params={'offset': -1}, shot=(1, 1000))
motion = np.zeros((h, w, 2), np.float32)
for i in range(1000):
    nprfx.render('threshold-map', inputs=inputs, params=params, threads=1)
    n.render(i + 1, {'image': motion})
    try:
        nprfx.render('threshold-map', inputs=inputs, params={'sigma': -1})
    except nprfx.Error:
        pass
del n
grown = rss_mb() - rss
check([sys.getrefcount(o) for o in (tone, pattern, inputs, params, 'builtin')] == refs,
      'reference counts changed over 1,000 renders')
check(grown < 8, 'the resident size grew %.1f MB over 1,000 renders' % grown)

finish('python module: passed')
