"""Every node through the Python module gives the runner's pixels, bit for bit: each node of
nprfx.nodes() is rendered by `nprfx run` (a graph reading the plates, writing float EXRs) and by
the module on the same channels read with OpenImageIO's Python module; temporal nodes over a
three-frame shot, through nprfx.Node with a fetch callable and, where a node fetches only the
past, also with no callable (the inputs given to its earlier renders). A node missing from the
table below fails the test, so a new node needs a line here.
usage: python3 test_nodes.py NPRFX WORK_DIR (PYTHONPATH: the build's python/ folder)"""
import json
import os
import subprocess
import sys

from checks import check, finish, read

import numpy as np

import nprfx

runner, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
os.chdir(work)
FRAMES = (1, 2, 3)
subprocess.run([runner, 'synth', 'orbit', '-o', 'plate.####.exr', '--frames', '1-3', '--size',
                '160x90'], check=True, capture_output=True)


plates = {f: read('plate.%04d.exr' % f) for f in FRAMES}


def channels(frame, names):
    have, px = plates[frame]
    return np.ascontiguousarray(px[:, :, [have.index(n) for n in names]])


RGB, PREF, MPREV = ['R', 'G', 'B'], ['Pref.X', 'Pref.Y', 'Pref.Z'], ['motion_prev.X', 'motion_prev.Y']
# node: ({input: plate channels}, params, fetches only the past)
CASES = {
    'advect': ({'motion_prev': MPREV}, {}, True),
    'blend': ({'base': RGB, 'layer': ['albedo.R', 'albedo.G', 'albedo.B'], 'alpha': ['diffuse']},
              {'mode': 'multiply'}, False),
    'bump': ({'image': RGB, 'height': ['diffuse']}, {}, False),
    'coherent-noise': ({'depth': ['Z'], 'motion_prev': MPREV}, {'channels': 2}, True),
    'flow': ({'image': RGB}, {}, False),
    'gabor-splat': ({'anchor': PREF, 'depth': ['Z'], 'id': ['id']}, {'radius': 6}, False),
    'lines': ({'id': ['id'], 'depth': ['Z'], 'normal': ['N.X', 'N.Y', 'N.Z']}, {}, False),
    'matte': ({'depth': ['Z'], 'id': ['id']}, {'soften': 1.5}, False),
    'morphology': ({'image': ['diffuse']}, {}, False),
    'pam-splat': ({'anchor': PREF, 'tone': ['diffuse'], 'color': RGB + ['A'], 'depth': ['Z'],
                   'id': ['id']}, {'size': 10}, False),
    'paper': ({'image': RGB}, {}, False),
    'stipple': ({'tone': ['diffuse'], 'uv': ['UV.U', 'UV.V'], 'id': ['id']}, {'size': 3}, False),
    'threshold-map': ({'pattern': ['albedo.G'], 'tone': ['diffuse']}, {}, False),
    'time-offset': ({'image': RGB}, {'offset': -1}, True),
    'tone': ({'tone': ['diffuse']}, {}, False),
    'warp': ({'image': RGB, 'offset': MPREV}, {}, False),
    'watercolor': ({'image': RGB, 'coverage': ['coverage']}, {}, False),
}


def fail(what):
    check(False, what)


nodes = nprfx.nodes()
for missing in sorted(set(nodes) - set(CASES)):
    fail('%s has no case in test_nodes.py' % missing)

# The runner: one graph, every node, the shot 1-3 (the non-temporal ones are compared at 2).
graph = {'frames': '1-3', 'nodes': {'plate': {'node': 'read', 'path': 'plate.####.exr'}}}
for node, (inputs, params, _) in CASES.items():
    graph['nodes']['n_' + node] = {
        'node': node, 'params': params,
        'inputs': {k: 'plate:' + ','.join(v) for k, v in inputs.items()}}
    graph['nodes']['w_' + node] = {'node': 'write', 'inputs': {'image': 'n_' + node},
                                   'path': 'runner/%s.####.exr' % node, 'preview': ''}
with open('graph.json', 'w') as f:
    json.dump(graph, f)
r = subprocess.run([runner, 'run', 'graph.json', '--quiet', '--analysis', 'off'],
                   capture_output=True, text=True)
if r.returncode:
    sys.exit('FAIL: the runner failed:\n' + r.stderr)


def same(node, frame, got, names, how):
    """got (channels named as the Node names them) against the runner's file, whose channels
    OpenImageIO gives in the file's order"""
    have, want = read('runner/%s.%04d.exr' % (node, frame))
    if have is None:
        fail('%s frame %d: the runner wrote no file' % (node, frame))
        return
    if sorted(have) != sorted(names):
        fail('%s frame %d (%s): channels %s, the runner %s' % (node, frame, how, names, have))
        return
    want = np.ascontiguousarray(want[:, :, [have.index(c) for c in names]])
    if got.shape != want.shape:
        fail('%s frame %d (%s): shape %s, the runner %s' % (node, frame, how, got.shape, want.shape))
    elif not np.array_equal(got.view(np.uint32), want.view(np.uint32)):
        d = np.nanmax(np.abs(got.astype(np.float64) - want))
        n = int(np.count_nonzero(got.view(np.uint32) != want.view(np.uint32)))
        fail('%s frame %d (%s): %d values differ from the runner (up to %g)' % (node, frame, how,
                                                                                  n, d))


for node, (inputs, params, past_only) in CASES.items():
    if node not in nodes:
        continue
    if not nodes[node].temporal:
        got = nprfx.render(node, inputs={k: channels(2, v) for k, v in inputs.items()},
                           params=params, frame=2, threads=2)
        n = nprfx.Node(node, params=params, threads=1)
        again = n.render(2, {k: channels(2, v) for k, v in inputs.items()})
        if not np.array_equal(got.view(np.uint32), again.view(np.uint32)):
            fail('%s: render() and Node.render differ' % node)
        same(node, 2, got, n.channels, 'render')
        continue
    n = nprfx.Node(node, params=params, threads=2, shot=(1, 3),
                   fetch=lambda name, f: channels(f, inputs[name]))
    for f in FRAMES:
        got = n.render(f, {k: channels(f, v) for k, v in inputs.items()})
        same(node, f, got, n.channels, 'Node, fetch')
    if past_only:
        n = nprfx.Node(node, params=params, threads=1, shot=(1, 3))
        for f in FRAMES:
            got = n.render(f, {k: channels(f, v) for k, v in inputs.items()})
            same(node, f, got, n.channels, 'Node in order')

finish('python nodes: %d nodes equal to the runner' % len(CASES))
