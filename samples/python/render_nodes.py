#!/usr/bin/env python3
"""Toon shading with ink lines, node by node from Python: plates read with OpenImageIO's Python
module, nprfx's nodes on the NumPy arrays, the frames written back with OpenImageIO (EXR, and a
PNG to look at). The same look as samples/graphs/toon.json, built in code instead of a graph
file: a pipeline script can put its own steps between the nodes.

    PYTHONPATH=build/python python3 samples/python/render_nodes.py [--frames 1-24] [--out DIR]

The tone node measures its range over the whole shot, so it is a Node whose fetch callable reads
any frame of the plates; the others render frame by frame."""
import argparse
import os

import numpy as np
import OpenImageIO as oiio

import nprfx

HERE = os.path.dirname(os.path.abspath(__file__))
PLATES = os.path.join(HERE, '..', 'plates', 'crossing', 'crossing.%04d.exr')


def read_plate(frame, cache={}):
    """The channels of a plate by name, as float32 arrays (H x W x C), cached."""
    if frame not in cache:
        inp = oiio.ImageInput.open(PLATES % frame)
        if not inp:
            raise SystemExit('cannot read %s: %s' % (PLATES % frame, oiio.geterror()))
        names = list(inp.spec().channelnames)
        px = inp.read_image(oiio.FLOAT)
        inp.close()
        cache[frame] = (names, px)
    return cache[frame]


def channels(frame, layer, names):
    have, px = read_plate(frame)
    return np.ascontiguousarray(px[:, :, [have.index('ViewLayer.%s.%s' % (layer, n)) for n in names]])


def inputs_of(frame):
    return {
        'beauty': channels(frame, 'Combined', 'RGB'),
        'alpha': channels(frame, 'Combined', 'A'),
        'depth': channels(frame, 'Depth', 'Z'),
        'id': channels(frame, 'IndexOB', 'X'),
        'albedo': channels(frame, 'DiffCol', 'RGB'),
        'normal': channels(frame, 'Normal', 'XYZ'),
    }


def write(path, image, preview=None):
    h, w, c = image.shape
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(w, h, c, oiio.FLOAT))
    out.write_image(image)
    out.close()
    if preview:
        buf = oiio.ImageBuf(np.ascontiguousarray(image[:, :, :3]))
        buf = oiio.ImageBufAlgo.colorconvert(buf, 'linear', 'sRGB')
        buf.write(preview, 'uint8')


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--frames', default='1-24', help='first-last (default 1-24)')
    ap.add_argument('--out', default='out/python_toon', help='output folder')
    args = ap.parse_args()
    first, last = (int(x) for x in args.frames.split('-'))
    os.makedirs(args.out, exist_ok=True)

    def matte_of(p):
        return nprfx.render('matte', inputs={'depth': p['depth'], 'id': p['id']})

    # the light cut into 3 bands: tone measures its range over the shot, fetching its inputs at
    # any frame (the coverage it weighs them by is that frame's matte)
    def fetch(name, frame):
        p = inputs_of(frame)
        if name == 'coverage':
            return matte_of(p)
        return {'tone': p['beauty'], 'albedo': p['albedo']}[name]
    bands = nprfx.Node('tone', params={'bands': 3, 'band_softness': 0.08, 'out_low': 0.45,
                                       'low': 2, 'high': 95}, shot=(1, 24), fetch=fetch)
    for frame in range(first, last + 1):
        p = inputs_of(frame)
        matte = matte_of(p)
        band = bands.render(frame, {'tone': p['beauty'], 'albedo': p['albedo'], 'coverage': matte})
        shade = nprfx.render('blend', inputs={'base': p['albedo'], 'layer': band},
                             params={'mode': 'multiply', 'gain_base': 1.1})
        ink = nprfx.render('lines', inputs={'id': p['id'], 'depth': p['depth'],
                                            'normal': p['normal']},
                           params={'width': 1.0, 'crease_angle': 40})
        paper = nprfx.render('paper', inputs={'image': p['beauty']}, params={'kind': 'paper'})
        toon = nprfx.render('blend', inputs={'base': paper, 'layer': shade, 'alpha': matte},
                            params={'mode': 'alphablend'})
        look = nprfx.render('blend', inputs={'base': toon, 'layer': ink, 'alpha': ink},
                            params={'mode': 'alphablend', 'gain_layer': 0.05})
        base = os.path.join(args.out, 'toon.%04d' % frame)
        write(base + '.exr', look, base + '.png')
        print('frame %d: %s.exr' % (frame, base))


if __name__ == '__main__':
    main()
