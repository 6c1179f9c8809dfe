"""What the Python module's tests share: counted checks and EXR pixels through OpenImageIO."""
import sys

failures = []


def check(cond, what):
    """Count a failed property, printing what failed."""
    if not cond:
        failures.append(what)
        print('FAIL: ' + what)


def finish(passed):
    """Exit 1 when any check failed, else print the passing line."""
    if failures:
        sys.exit(1)
    print(passed)


def read(path):
    """(channel names, H x W x C float32 pixels) of an image, or (None, None) when unreadable."""
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(path)
    if not inp:
        return None, None
    names = list(inp.spec().channelnames)
    px = inp.read_image(oiio.FLOAT)
    inp.close()
    return names, px.reshape(px.shape[0], px.shape[1], -1)


def pixels(path):
    return read(path)[1]
