"""Every node through the Python module gives the runner's pixels, bit for bit: each node of
nprfx.nodes() is rendered by `nprfx run` (a graph reading the plates, writing float EXRs) and by
the module on the same channels read with OpenImageIO's Python module, on synthetic plates and
on the bundled crossing shot; temporal nodes over a three-frame shot, through nprfx.Node with a
fetch callable and, where a node fetches only the past, also with no callable (the inputs given
to its earlier renders). A node missing from the
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
subprocess.run([runner, 'synth', 'orbit', '-o', 'orbit.####.exr', '--frames', '1-3', '--size',
                '160x90'], check=True, capture_output=True)
src = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The plates: nprfx synth's orbit, and the bundled crossing shot (Blender's layout, half floats),
# each AOV the cases use by its channels there.
V = 'ViewLayer.'
PLATES = {
    'orbit': (os.path.abspath('orbit.####.exr'), {
        'rgb': ['R', 'G', 'B'], 'a': ['A'], 'z': ['Z'], 'id': ['id'], 'coverage': ['coverage'],
        'diffuse': ['diffuse'], 'albedo': ['albedo.R', 'albedo.G', 'albedo.B'],
        'pref': ['Pref.X', 'Pref.Y', 'Pref.Z'], 'n': ['N.X', 'N.Y', 'N.Z'],
        'uv': ['UV.U', 'UV.V'], 'mprev': ['motion_prev.X', 'motion_prev.Y']}),
    'crossing': (os.path.join(src, 'samples', 'plates', 'crossing', 'crossing.####.exr'), {
        'rgb': [V + 'Combined.' + c for c in 'RGB'], 'a': [V + 'Combined.A'],
        'z': [V + 'Depth.Z'], 'id': [V + 'IndexOB.X'], 'coverage': [V + 'Combined.A'],
        'diffuse': [V + 'DiffDir.R'], 'albedo': [V + 'DiffCol.' + c for c in 'RGB'],
        'pref': [V + 'Pref.' + c for c in 'RGB'], 'n': [V + 'Normal.' + c for c in 'XYZ'],
        'uv': [V + 'UV.U', V + 'UV.V'], 'mprev': [V + 'Vector.X', V + 'Vector.Y']}),
}
# node: ({input: AOVs}, params, fetches only the past)
CASES = {
    'advect': ({'motion_prev': ['mprev']}, {}, True),
    'blend': ({'base': ['rgb'], 'layer': ['albedo'], 'alpha': ['diffuse']}, {'mode': 'multiply'},
              False),
    'bump': ({'image': ['rgb'], 'height': ['diffuse']}, {}, False),
    'coherent-noise': ({'depth': ['z'], 'motion_prev': ['mprev']}, {'channels': 2}, True),
    'flow': ({'image': ['rgb']}, {}, False),
    'gabor-splat': ({'anchor': ['pref'], 'depth': ['z'], 'id': ['id']}, {'radius': 6}, False),
    'lines': ({'id': ['id'], 'depth': ['z'], 'normal': ['n']}, {}, False),
    'matte': ({'depth': ['z'], 'id': ['id']}, {'soften': 1.5}, False),
    'morphology': ({'image': ['diffuse']}, {}, False),
    'pam-splat': ({'anchor': ['pref'], 'tone': ['diffuse'], 'color': ['rgb', 'a'], 'depth': ['z'],
                   'id': ['id']}, {'size': 10}, False),
    'paper': ({'image': ['rgb']}, {}, False),
    'stipple': ({'tone': ['diffuse'], 'uv': ['uv'], 'id': ['id']}, {'size': 3}, False),
    'threshold-map': ({'pattern': ['albedo'], 'tone': ['diffuse']}, {}, False),
    'time-offset': ({'image': ['rgb']}, {'offset': -1}, True),
    'tone': ({'tone': ['diffuse']}, {}, False),
    'warp': ({'image': ['rgb'], 'offset': ['mprev']}, {}, False),
    'watercolor': ({'image': ['rgb'], 'coverage': ['coverage']}, {}, False),
}


def fail(what):
    check(False, what)


nodes = nprfx.nodes()
for missing in sorted(set(nodes) - set(CASES)):
    fail('%s has no case in test_nodes.py' % missing)


def same(node, path, got, names, how):
    """got (channels named as the Node names them) against the runner's file, whose channels
    OpenImageIO gives in the file's order"""
    have, want = read(path)
    if have is None:
        fail('%s: the runner wrote no file' % path)
        return
    if sorted(have) != sorted(names):
        fail('%s (%s): channels %s, the runner %s' % (path, how, names, have))
        return
    want = np.ascontiguousarray(want[:, :, [have.index(c) for c in names]])
    if got.shape != want.shape:
        fail('%s (%s): shape %s, the runner %s' % (path, how, got.shape, want.shape))
    elif not np.array_equal(got.view(np.uint32), want.view(np.uint32)):
        d = np.nanmax(np.abs(got.astype(np.float64) - want))
        n = int(np.count_nonzero(got.view(np.uint32) != want.view(np.uint32)))
        fail('%s (%s): %d values differ from the runner (up to %g)' % (path, how, n, d))


compared = 0
for plate, (pattern, aovs) in PLATES.items():
    frames = {f: read(pattern.replace('####', '%04d' % f)) for f in FRAMES}

    def channels(frame, wanted):
        have, px = frames[frame]
        names = [c for a in wanted for c in aovs[a]]
        return np.ascontiguousarray(px[:, :, [have.index(n) for n in names]])

    # the runner: one graph, every node, the shot 1-3 (the non-temporal ones compared at 2)
    graph = {'frames': '1-3', 'nodes': {'plate': {'node': 'read', 'path': pattern}}}
    for node, (inputs, params, _) in CASES.items():
        graph['nodes']['n_' + node] = {
            'node': node, 'params': params,
            'inputs': {k: 'plate:' + ','.join(c for a in v for c in aovs[a])
                       for k, v in inputs.items()}}
        graph['nodes']['w_' + node] = {'node': 'write', 'inputs': {'image': 'n_' + node},
                                       'path': '%s/%s.####.exr' % (plate, node), 'preview': ''}
    with open(plate + '.json', 'w') as f:
        json.dump(graph, f)
    r = subprocess.run([runner, 'run', plate + '.json', '--quiet', '--analysis', 'off'],
                       capture_output=True, text=True)
    if r.returncode:
        sys.exit('FAIL: the runner failed on %s:\n%s' % (plate, r.stderr))

    for node, (inputs, params, past_only) in CASES.items():
        if node not in nodes:
            continue
        out = '%s/%s.%%04d.exr' % (plate, node)
        if not nodes[node].temporal:
            ins = {k: channels(2, v) for k, v in inputs.items()}
            got = nprfx.render(node, inputs=ins, params=params, frame=2, threads=2)
            n = nprfx.Node(node, params=params, threads=1)
            again = n.render(2, ins)
            if not np.array_equal(got.view(np.uint32), again.view(np.uint32)):
                fail('%s on %s: render() and Node.render differ' % (node, plate))
            same(node, out % 2, got, n.channels, 'render')
            compared += 1
            continue
        n = nprfx.Node(node, params=params, threads=2, shot=(1, 3),
                       fetch=lambda name, f: channels(f, inputs[name]))
        for f in FRAMES:
            got = n.render(f, {k: channels(f, v) for k, v in inputs.items()})
            same(node, out % f, got, n.channels, 'Node, fetch')
            compared += 1
        if past_only:
            n = nprfx.Node(node, params=params, threads=1, shot=(1, 3))
            for f in FRAMES:
                got = n.render(f, {k: channels(f, v) for k, v in inputs.items()})
                same(node, out % f, got, n.channels, 'Node in order')

finish('python nodes: %d nodes on %d plates, %d frames equal to the runner' % (
    len(CASES), len(PLATES), compared))
