"""nprfx.Graph runs a graph with the runner's engine: the same files bit for bit as `nprfx run`
(a look on the synthetic orbit plates), with frames, shot, threads, a memory limit and a
progress callable; the costs come back as --stats has them; errors are nprfx.Error with the
runner's words (checked against its stderr).
usage: python3 test_graph.py NPRFX WORK_DIR (PYTHONPATH: the build's python/ folder)"""
import json
import os
import subprocess
import sys

from checks import check, finish, pixels

import numpy as np

import nprfx

runner, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
os.chdir(work)


graph = {
    'frames': '1-4',
    'nodes': {
        'plate': {'node': 'synth', 'scene': 'orbit', 'size': '128x72'},
        'noise': {'node': 'coherent-noise', 'inputs': {'depth': 'plate:Z', 'motion_prev': 'plate'},
                  'params': {'seed': 3, 'output': 'unit01'}},
        'hatch': {'node': 'threshold-map', 'inputs': {'pattern': 'noise', 'tone': 'plate:diffuse'},
                  'params': {'mode': 'builtin'}},
        'ink': {'node': 'lines', 'inputs': {'id': 'plate:id', 'depth': 'plate:Z'}},
        'out': {'node': 'blend', 'inputs': {'base': 'hatch', 'layer': 'ink'}, 'params': {'mode': 'multiply'}},
        'w': {'node': 'write', 'inputs': {'image': 'out'}, 'path': 'OUT/look.####.exr', 'preview': ''},
    }}
with open('look.json', 'w') as f:
    json.dump(graph, f)
subprocess.run([runner, 'run', 'look.json', '--quiet', '--set', 'w.path=runner/look.####.exr'],
               check=True)

# load and from_dict, every frame equal to the runner's
seen = []
g = nprfx.Graph.load('look.json', threads=2)
g.set('w.path', 'load/look.####.exr')
plan = g.check()
check(plan.frames == [1, 2, 3, 4] and plan.plan.peak > 0, 'check: %s' % plan)
r = g.run(progress=lambda rec: seen.append((rec.frame, rec.ok, rec.written)))
check(seen == [(f, True, 1) for f in (1, 2, 3, 4)], 'progress records: %s' % seen)
check(r.rendered == 4 and r.failed == 0 and r.files == 4, 'summary: %s' % r)
check({'plate', 'noise', 'hatch', 'ink', 'out', 'w'} <= {s.name for s in r.stats},
      'stats names: %s' % [s.name for s in r.stats])
check(all(s.calls >= 1 for s in r.stats) and r.mem_peak > 0, 'stats: %s' % r.stats)
d = dict(graph)
d['nodes'] = dict(graph['nodes'])
d['nodes']['w'] = dict(graph['nodes']['w'], path='dict/look.####.exr')
g2 = nprfx.Graph.from_dict(d, threads=1, mem_limit='200M')
r2 = g2.run(frames='2-3', serial=True)
check(r2.rendered == 2 and [f.frame for f in r2.frames] == [2, 3], 'frames 2-3: %s' % r2.frames)
for f in (1, 2, 3, 4):
    want = pixels('runner/look.%04d.exr' % f)
    for how in ('load', 'dict'):
        got = pixels('%s/look.%04d.exr' % (how, f))
        if how == 'dict' and f in (1, 4):
            check(got is None, 'frame %d was rendered though frames were 2-3' % f)
            continue
        check(got is not None and want is not None and
              np.array_equal(got.view(np.uint32), want.view(np.uint32)),
              '%s frame %d differs from the runner' % (how, f))
# eval: a node's result without writing, equal to the written frame
e = g.eval('out', 3)
check(np.array_equal(e[:, :, 0], pixels('runner/look.0003.exr')[:, :, 0]), 'eval differs')

# knobs: the graph's params worth turning, with its words and the param's description
src = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
hatching = nprfx.Graph.load(os.path.join(src, 'samples', 'graphs', 'cross_hatching.json'))
knobs = {k.name: k for k in hatching.knobs()}
k = knobs.get('strokes*.frequency')
check(k is not None and k.nodes == 2 and k.help == 'stroke spacing' and k.type == 'gabor-splat'
      and k.param.name == 'frequency' and k.param.max > k.param.min, 'knob: %s' % k)
hatching.set('strokes*.frequency', 0.25)
check({x.name: x.value for x in hatching.knobs()}['strokes*.frequency'] == 0.25,
      'set through a knob did not change it')

# a progress callable that raises stops the run, and its exception reaches the caller
class Stop(Exception):
    pass


def stop(rec):
    raise Stop(rec.frame)


try:
    nprfx.Graph.load('look.json').run(progress=stop)
    check(False, 'a raising progress did not stop the run')
except Stop as e:
    check(e.args == (1,), 'stopped at %s' % (e.args,))

# errors: the runner's words
def runner_error(*args):
    p = subprocess.run([runner, 'run', 'look.json', '--quiet'] + list(args), capture_output=True,
                       text=True)
    return p.stderr.strip()


def module_error(call):
    try:
        call()
    except nprfx.Error as e:
        return str(e)
    return None


words = runner_error('--set', 'hatch.sigma=-3')
got = module_error(lambda: nprfx.Graph.load('look.json').set('hatch.sigma', -3))
check(got and got in words, 'set error %r is not the runner\'s %r' % (got, words))
words = runner_error('--frames', '7')
got = module_error(lambda: nprfx.Graph.load('look.json').run(frames='7'))
check(got and got in words, 'frames error %r is not the runner\'s %r' % (got, words))
got = module_error(lambda: nprfx.Graph.load('no_such.json'))
check(got and 'no_such.json' in got, 'a missing graph file: %r' % got)
got = module_error(lambda: nprfx.Graph.from_dict({'nodes': {'x': {'node': 'nope'}}}))
check(got and 'nope' in got, 'an unknown node: %r' % got)
got = module_error(lambda: nprfx.Graph.load('look.json', mem_limit='lots'))
check(got and 'lots' in got, 'a bad memory limit: %r' % got)

finish('python graph: passed')
