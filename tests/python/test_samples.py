"""The Python samples run as their docstrings say: samples/python/render_nodes.py writes EXR and
PNG frames of its look, non-blank; samples/python/run_graph.py writes toon.json's frames equal,
bit for bit, to `nprfx run`'s.
usage: python3 test_samples.py NPRFX WORK_DIR (PYTHONPATH: the build's python/ folder)"""
import os
import subprocess
import sys

from checks import check, finish, pixels

import numpy as np


runner, work = sys.argv[1], sys.argv[2]
src = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
samples = os.path.join(src, 'samples', 'python')
os.makedirs(work, exist_ok=True)
os.chdir(work)


def run(*args):
    p = subprocess.run([sys.executable] + list(args), capture_output=True, text=True)
    check(p.returncode == 0, '%s failed:\n%s' % (' '.join(args), p.stderr))


run(os.path.join(samples, 'render_nodes.py'), '--frames', '1-2', '--out', 'nodes')
for f in (1, 2):
    px = pixels('nodes/toon.%04d.exr' % f)
    check(px is not None and px.shape == (180, 320, 4) and float(np.std(px[:, :, :3])) > 0.05,
          'render_nodes.py frame %d: missing or flat' % f)
    check(os.path.exists('nodes/toon.%04d.png' % f), 'render_nodes.py wrote no PNG')

graph = os.path.join(src, 'samples', 'graphs', 'toon.json')
run(os.path.join(samples, 'run_graph.py'), graph, '--frames', '1-2', '--out', 'module')
subprocess.run([runner, 'run', graph, '--frames', '1-2', '--output-dir', 'runner', '--quiet'],
               check=True)
for f in (1, 2):
    a, b = pixels('module/out/toon/toon.%04d.exr' % f), pixels('runner/out/toon/toon.%04d.exr' % f)
    check(a is not None and b is not None and np.array_equal(a.view(np.uint32), b.view(np.uint32)),
          'run_graph.py frame %d differs from nprfx run' % f)

finish('python samples: passed')
