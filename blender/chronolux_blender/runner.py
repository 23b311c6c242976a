"""Running the ``chronolux`` binary: its command line, its progress lines, cancellation.
No bpy here, so that it can be tested and reused outside Blender."""

import os
import queue
import re
import shutil
import subprocess
import threading
import time

# The binary's per-frame line when stderr is not a terminal (crates/chronolux/src/render.rs,
# `Progress::frame`): "frame 12 [ 3/49] t=0.500 s: ...".
FRAME_LINE = re.compile(r"^frame (-?\d+) \[\s*(\d+)/(\d+)\]")

# Methods with a quality table (`chronolux render --help`, --quality): others reject it.
QUALITY_METHODS = ("spacetime-dept", "stbpt", "path")


class RunError(Exception):
    pass


class Cancelled(Exception):
    pass


def find_binary(configured):
    """The binary to run: the add-on preference, else $CHRONOLUX_BINARY, else `chronolux` on
    PATH. Raises RunError naming what was tried."""
    for cand in (configured, os.environ.get("CHRONOLUX_BINARY", "")):
        if cand:
            cand = os.path.expanduser(cand)
            if os.path.isfile(cand) and os.access(cand, os.X_OK):
                return cand
            raise RunError("the Chronolux binary '%s' does not exist or is not executable "
                           "(Preferences > Add-ons > Chronolux)" % cand)
    found = shutil.which("chronolux")
    if found:
        return found
    raise RunError("no Chronolux binary: set its path in Preferences > Add-ons > Chronolux "
                   "(build it with `cargo build --release`: target/release/chronolux)")


def command(binary, scene, output, frames, fps, resolution, camera, method, quality,
            denoise, environment=None, spp=0, extra=()):
    """The argument list of one temporal run over ``frames`` = (first, last), inclusive."""
    a, b = frames
    cmd = [binary, "render", scene,
           "--output", output,
           "--frames", "%d..=%d" % (a, b) if b != a else str(a),
           "--fps", repr(float(fps)),
           "--resolution", "%dx%d" % resolution,
           "--method", method,
           "--passes", "albedo,normal,depth",
           "--exposure", "0",  # PNGs only; skips measuring an automatic exposure
           "--no-preview"]
    if camera:
        cmd += ["--camera", camera]
    if method in QUALITY_METHODS:
        cmd += ["--quality", quality]
    cmd += ["--denoise"] if denoise else ["--no-denoise"]
    if spp:
        cmd += ["--spp", str(int(spp))]
    if environment is not None:
        path, strength, rotation = environment
        cmd += ["--environment", path,
                "--environment-strength", repr(float(strength)),
                "--environment-rotation", repr(float(rotation))]
    cmd += list(extra)
    return cmd


def run(cmd, should_stop, on_line, poll=0.05, grace=5.0):
    """Runs ``cmd``; every stderr/stdout line goes to ``on_line(line, fraction)``
    (fraction: frames done / frames, or None). ``should_stop()`` is polled every ``poll``
    seconds: when true the process is terminated (killed after ``grace`` seconds) and
    Cancelled raised. A non-zero exit raises RunError with the last lines."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            stdin=subprocess.DEVNULL, text=True, bufsize=1,
                            errors="replace")
    lines = queue.Queue()

    def pump():
        for line in proc.stdout:
            lines.put(line.rstrip("\n"))
        lines.put(None)

    reader = threading.Thread(target=pump, daemon=True)
    reader.start()
    tail = []
    done_reading = False
    try:
        while True:
            try:
                while True:
                    line = lines.get_nowait()
                    if line is None:
                        done_reading = True
                        break
                    tail = (tail + [line])[-20:]
                    m = FRAME_LINE.match(line)
                    on_line(line, int(m.group(2)) / int(m.group(3)) if m else None)
            except queue.Empty:
                pass
            if done_reading and proc.poll() is not None:
                break
            if should_stop():
                raise Cancelled()
            time.sleep(poll)
    except BaseException:
        stop(proc, grace)
        # The reader sees the pipe close; joined so that no thread outlives the call.
        reader.join(grace)
        raise
    if proc.returncode != 0:
        raise RunError("chronolux exited with status %d:\n%s" % (proc.returncode, "\n".join(tail[-8:])))


def stop(proc, grace):
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(grace)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
