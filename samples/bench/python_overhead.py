#!/usr/bin/env python3
"""A node through the Python module next to `nprfx bench` of the same node, size and threads:
what a render through Python adds (the copies of the inputs and the result, numpy's fresh
pages, a context and worker pool per nprfx.render() call, none per Node.render).

    PYTHONPATH=build/python python3 samples/bench/python_overhead.py build/nprfx [THREADS]"""
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import OpenImageIO as oiio

import nprfx

runner = sys.argv[1]
threads = int(sys.argv[2]) if len(sys.argv) > 2 else 2
CASES = {  # node: ({input: synth channels}, params, --set for the bench)
    'threshold-map': ({'pattern': ['diffuse'], 'tone': ['diffuse']}, {'mode': 'builtin'},
                      ['--set', 'mode=builtin']),
    'gabor-splat': ({'anchor': ['Pref.X', 'Pref.Y', 'Pref.Z'], 'depth': ['Z']}, {}, []),
}


def timed(fn, n):
    fn()
    ts = []
    for _ in range(n):
        t = time.perf_counter()
        fn()
        ts.append((time.perf_counter() - t) * 1000)
    return sum(ts) / n, min(ts)


with tempfile.TemporaryDirectory() as tmp:
    print('| node | size | nprfx bench ms (best) | Node.render ms (best) | nprfx.render() ms |')
    print('|---|---|---|---|---|')
    for size in ('320x180', '1920x1080'):
        plate = os.path.join(tmp, 'orbit_%s.exr' % size)
        subprocess.run([runner, 'synth', 'orbit', '-o', plate, '--size', size], check=True,
                       capture_output=True)
        inp = oiio.ImageInput.open(plate)
        names = list(inp.spec().channelnames)
        px = inp.read_image(oiio.FLOAT)
        inp.close()
        for node, (wiring, params, bench_set) in CASES.items():
            ins = {k: np.ascontiguousarray(px[:, :, [names.index(c) for c in v]])
                   for k, v in wiring.items()}
            n = 30 if size == '320x180' else 8
            out = subprocess.run([runner, 'bench', node, '--size', size, '--threads',
                                  str(threads)] + bench_set, capture_output=True, text=True,
                                 check=True).stdout.splitlines()[0]
            bench = out.split(': ')[1].split(' ms/frame')[0]
            best = out.split('(best ')[1].split(';')[0]
            nd = nprfx.Node(node, params=params, threads=threads)
            mean, low = timed(lambda: nd.render(1, ins), n)
            once, _ = timed(lambda: nprfx.render(node, inputs=ins, params=params,
                                                 threads=threads), n)
            print('| %s | %s | %s (%s) | %.2f (%.2f) | %.2f |' % (node, size, bench, best, mean,
                                                                low, once))
