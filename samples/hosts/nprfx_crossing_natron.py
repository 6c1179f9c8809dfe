# nprfx sample for Natron 2.x: the coloured-pencil look of samples/graphs/main.json, built from
# the nprfx OpenFX plug-ins on the Blender "crossing" plates, then saved as nprfx_crossing.ntp
# beside this script. See samples/hosts/README.md.
#
#   OFX_PLUGIN_PATH=build/plugins/ofx Natron -t samples/hosts/nprfx_crossing_natron.py
#   (or paste it into Natron's Script Editor)
#
# OFX clips only carry RGBA, so each AOV is shuffled into RGBA first and the node's channel
# selector (depthChannels, motionPrevChannels, ...) says which components to read. Blender's
# Vector pass has y up and nprfx's motion vectors y down: a Multiply by (1, -1, 1, -1) turns
# (X, Y, Z, W) into motion_prev = (X, -Y), motion_next = (Z, -W), as `vectors: blender` does in
# the runner. Natron names its Shuffle options after the layers it finds in the file
# (ViewLayer.Depth, ...), which differ between versions: the script looks them up by suffix.

import os

import NatronEngine  # noqa: F401  (provided by Natron)

HERE = os.path.dirname(os.path.abspath(__file__))
PLATES = os.path.join(HERE, "..", "plates", "crossing", "crossing.####.exr")


def choose(param, *wanted):
    """Set a choice param to the first option whose label ends with one of `wanted`."""
    options = [param.getOption(i) for i in range(param.getNumOptions())]
    for w in wanted:
        for i, o in enumerate(options):
            if o == w or o.endswith(w):
                param.setValue(i)
                return o
    print("nprfx sample: %s has none of %s among %s" % (param.getScriptName(), wanted, options))
    return None


def shuffle(app, src, layer, channels, name):
    """A Shuffle that puts `channels` of `layer` into R, G, B, A (the last repeats)."""
    node = app.createNode("net.sf.openfx.ShufflePlugin")
    node.setScriptName(name)
    node.connectInput(0, src)
    for k, out in enumerate(("outputR", "outputG", "outputB", "outputA")):
        c = channels[min(k, len(channels) - 1)]
        choose(node.getParam(out), "%s.%s" % (layer, c))
    return node


def ofx(app, plugin, name, inputs, **params):
    node = app.createNode("org.nprfx." + plugin)
    node.setScriptName(name)
    # nprfx defines the Source clip first, then the others in the node's order
    for index, src in inputs.items():
        if src is not None:
            node.connectInput(index, src)
    for key, value in params.items():
        p = node.getParam(key)
        if isinstance(value, str):
            choose(p, value)
        else:
            p.setValue(value)
    return node


def build(app):
    app.getProjectParam("frameRange").set(1, 24)
    read = app.createReader(PLATES)
    read.setScriptName("ReadCrossing")

    depth = shuffle(app, read, "Depth", ["Z"], "DepthToRGBA")
    vector = shuffle(app, read, "Vector", ["X", "Y", "Z", "W"], "VectorToRGBA")
    flip = app.createNode("net.sf.openfx.MultiplyPlugin")
    flip.setScriptName("VectorYDown")
    flip.connectInput(0, vector)
    flip.getParam("value").set(1.0, -1.0, 1.0, -1.0)
    tone = shuffle(app, read, "DiffDir", ["R", "G", "B", "B"], "DiffDirToRGBA")
    albedo = shuffle(app, read, "DiffCol", ["R", "G", "B", "B"], "DiffColToRGBA")

    # coherent-noise clips: 0 Source (unused), 1 Depth, 2 MotionPrev, 3 MotionNext, 4 ZVelocity
    noise = ofx(app, "CoherentNoise", "CoherentNoise", {1: depth, 2: flip},
                noise="bandpass", sigma_lo=0.7, sigma_hi=2.5, alpha=0.9, output="unit01",
                contrast=0.2, depthChannels="R", motionPrevChannels="RG")
    # threshold-map clips: 0 Source (the pattern), 1 Tone, 2 Map
    strokes = ofx(app, "ThresholdMap", "ThresholdMap", {0: noise, 1: tone},
                  mode="builtin", sigma=20.0, tone_gain=1.0, sourceChannels="R",
                  toneChannels="R")
    # blend clips: 0 Source (the base), 1 Layer, 2 Back, 3 Alpha, 4 Coverage
    pencil = ofx(app, "Blend", "Pencil", {0: albedo, 1: strokes},
                 mode="multiply", sourceChannels="RGB", layerChannels="R")

    write = app.createWriter(os.path.join(HERE, "out", "pencil.####.exr"))
    write.setScriptName("WritePencil")
    write.connectInput(0, pencil)
    app.saveProjectAs(os.path.join(HERE, "nprfx_crossing.ntp"))


build(app)  # noqa: F821  (`app` is the project Natron runs the script in)
