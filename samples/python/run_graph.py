#!/usr/bin/env python3
"""A graph file run from Python by the engine of `nprfx run`: overrides, the shot, threads, a
memory limit, a progress line per frame, and the per-node costs of `nprfx run --stats`.

    PYTHONPATH=build/python python3 samples/python/run_graph.py [GRAPH] [--frames 1-4]
        [--set node.param=value ...] [--out DIR]

GRAPH defaults to samples/graphs/toon.json; its write paths are put under --out."""
import argparse
import os
import sys

import nprfx

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('graph', nargs='?', default=os.path.join(HERE, '..', 'graphs', 'toon.json'))
    ap.add_argument('--frames', default=None, help='frames to render (default: the graph\'s)')
    ap.add_argument('--set', action='append', default=[], metavar='NODE.PARAM=VALUE')
    ap.add_argument('--out', default='.', help='folder the write paths are relative to')
    ap.add_argument('--threads', type=int, default=0)
    ap.add_argument('--mem-limit', default=None, help='e.g. 2G')
    args = ap.parse_args()
    try:
        g = nprfx.Graph.load(args.graph, threads=args.threads, mem_limit=args.mem_limit,
                             output_dir=args.out)
        for s in args.set:
            what, _, value = s.partition('=')
            g.set(what, value)
        plan = g.check(frames=args.frames)
        print('%d frames, peak memory planned %.0f MiB (%s)' % (
            len(plan.frames), plan.plan.peak / 2**20, plan.plan.peak_node))

        def progress(rec):
            print('frame %d (%d/%d): %s, %.2f s' % (rec.frame, rec.done, rec.count,
                                                   'done' if rec.ok else rec.error, rec.seconds))
        result = g.run(frames=args.frames, progress=progress)
    except nprfx.Error as e:
        sys.exit('run_graph: %s' % e)
    for note in result.notices:
        print(note)
    print('%d frames, %d files in %.1f s, peak %.0f MiB' % (
        result.rendered, result.files, result.seconds, result.mem_peak / 2**20))
    for s in sorted(result.stats, key=lambda s: -s.seconds):
        print('  %-12s %-15s %4d calls %8.3f s' % (s.name, s.type, s.calls, s.seconds))


if __name__ == '__main__':
    main()
