# An example, not tested here: the farm render of nprfx farm (Slurm) as an OpenCue job, written
# as an outline script for OpenCue's pyoutline (what CueSubmit builds; `cuerun` or the launch
# below submits it). One Render layer runs the same chunk command as the Slurm array tasks, its
# chunk's first and last frame from OpenCue's #FRAME_START# and #FRAME_END# tokens; a Util layer
# of one task runs `nprfx farm check` after it.
#
# Change the paths, the range, the chunk and the cores to your shot; the working directory is
# where the write paths of the graph are relative to (the chunks run there).
import outline
import outline.cuerun
import outline.modules.shell

NPRFX = "/usr/bin/nprfx"
GRAPH = "/shows/demo/sh010/comp/noise.json"
WORKDIR = "/shows/demo/sh010/comp"
FRAMES = "1-2000"
CHUNK = 25
CORES = 8
# Whatever `nprfx farm ... --set` would pass to every chunk; --shot when the graph has no "frames".
COMMON = ["--shot", FRAMES, "--set", "noise.seed=7"]

job = outline.Outline("nprfx-sh010", shot="sh010", show="demo", user="td")

render = outline.modules.shell.Shell(
    "render",
    type="Render",
    command=["/bin/sh", "-c",
             "cd " + WORKDIR + " && exec " + " ".join(
                 [NPRFX, "run", GRAPH] + COMMON +
                 ["--frames", "#FRAME_START#-#FRAME_END#", "--threads", str(CORES),
                  "--shared-lock"])],
    range=FRAMES,
    chunk=CHUNK,
    threads=CORES,
)
job.add_layer(render)

check = outline.modules.shell.Shell(
    "check",
    type="Util",
    command=["/bin/sh", "-c",
             "cd " + WORKDIR + " && exec " + " ".join(
                 [NPRFX, "farm", "check", GRAPH, "--frames", FRAMES] + COMMON)],
    range="1",
    chunk=1,
)
# OpenCue runs a dependent layer once the layer it depends on is done; a chunk that failed for
# good must be eaten (or retried) for the check to run and list what is missing.
check.depend_on(render)
job.add_layer(check)

if __name__ == "__main__":
    outline.cuerun.launch(job, use_pycuerun=False)
