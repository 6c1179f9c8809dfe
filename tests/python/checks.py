"""What the Python module's tests share: counted checks and EXR pixels through OpenImageIO.
Imported first: without NumPy or OpenImageIO's Python module a test says so and exits 77, which
ctest counts as skipped."""
import sys

for _module, _package in (('numpy', 'python3-numpy'), ('OpenImageIO', 'python3-openimageio')):
    try:
        __import__(_module)
    except ImportError:
        print('SKIP: %s cannot import %s (Debian: %s; .ci/setup installs it)' % (
            sys.executable, _module, _package))
        sys.exit(77)

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
