"""The render engine: F12 renders the current frame; an animation render renders the whole
frame range as one temporal run of the binary, on its first frame, and hands Blender the
cached frames on the following calls."""

import os
import shutil
import tempfile

import bpy
import numpy as np

from . import exr, export, runner

# Passes Chronolux writes (`--passes albedo,normal,depth`, under Blender's names), with
# their channels: (name, channel ids, type) for register_pass / add_pass.
PASSES = (
    ("Denoising Albedo", "RGB", "COLOR"),
    ("Denoising Normal", "XYZ", "VECTOR"),
    ("Depth", "Z", "VALUE"),
)

# The animation run in progress. Blender calls render() once per frame and may make a new
# engine instance for each, so the run's frames are kept here, keyed by what identifies
# the animation render, until render_complete / render_cancel remove them.
_ANIMATION = {}


def _clear_animation(*_args):
    for entry in _ANIMATION.values():
        shutil.rmtree(entry["dir"], ignore_errors=True)
    _ANIMATION.clear()


def _size(scene):
    scale = scene.render.resolution_percentage / 100.0
    return (max(1, int(scene.render.resolution_x * scale)),
            max(1, int(scene.render.resolution_y * scale)))


def _prefs(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


class ChronoluxRenderEngine(bpy.types.RenderEngine):
    bl_idname = "CHRONOLUX"
    bl_label = "Chronolux"
    bl_use_preview = False
    bl_use_postprocess = True

    def update_render_passes(self, scene=None, renderlayer=None):
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        for name, chans, kind in PASSES:
            self.register_pass(scene, renderlayer, name, len(chans), chans, kind)

    def render(self, depsgraph):
        scene = depsgraph.scene
        try:
            self._render(scene, depsgraph)
        except runner.Cancelled:
            self.report({"WARNING"}, "Chronolux: render cancelled")
            _clear_animation()
            self._black_result(scene)
        except (export.ExportError, runner.RunError, exr.ExrError) as e:
            self.report({"ERROR"}, "Chronolux: %s" % e)
            _clear_animation()
            self._black_result(scene)

    def _black_result(self, scene):
        """A cancelled or failed frame still hands Blender a complete (black) result:
        Blender 5 headless crashes writing an animation frame whose Combined pass was
        never filled (measured: segmentation fault after a cancelled frame)."""
        w, h = _size(scene)
        result = self.begin_result(0, 0, w, h)
        try:
            combined = result.layers[0].passes.find_by_name("Combined", "")
            if combined is not None:
                combined.rect.foreach_set(np.zeros(w * h * 4, dtype=np.float32))
        finally:
            self.end_result(result)

    def _warn(self, msg):
        self.report({"WARNING"}, "Chronolux: %s" % msg)

    def _render(self, scene, depsgraph):
        frame = scene.frame_current
        size = _size(scene)
        # An animation render: `self.is_animation` is set by Blender for
        # `render.render(animation=True)` (Render Animation), in the UI and headless
        # (bpy from PyPI) alike, and read on each frame's call (tested headless:
        # blender/tests). screen.is_animation_playing is the viewport's playback, not a
        # render; is_job_running('RENDER') does not tell a still from an animation.
        if self.is_animation:
            key = (scene.name, scene.frame_start, scene.frame_end, size, str(scene.camera and scene.camera.name))
            entry = _ANIMATION.get(key)
            if entry is None or frame not in entry["frames"]:
                _clear_animation()
                first, last = scene.frame_start, scene.frame_end
                if not (first <= frame <= last):
                    first = last = frame
                entry = {"dir": tempfile.mkdtemp(prefix="chronolux-anim-"),
                         "frames": set(range(first, last + 1))}
                _ANIMATION[key] = entry
                self._run(scene, depsgraph, entry["dir"], (first, last), size)
            self._load(os.path.join(entry["dir"], "out"), frame, size)
        else:
            folder = tempfile.mkdtemp(prefix="chronolux-")
            try:
                self._run(scene, depsgraph, folder, (frame, frame), size)
                self._load(os.path.join(folder, "out"), frame, size)
            finally:
                shutil.rmtree(folder, ignore_errors=True)

    def _run(self, scene, depsgraph, folder, frames, size):
        props = scene.chronolux
        prefs = _prefs(bpy.context)
        binary = runner.find_binary(prefs.binary_path if prefs else "")
        self.update_stats("Chronolux", "exporting the scene (glTF)")
        glb = export.export_gltf(scene, depsgraph, folder, self._warn)
        env = export.world_environment(scene, folder, self._warn)
        fps = scene.render.fps / scene.render.fps_base
        cmd = runner.command(
            binary, glb, os.path.join(folder, "out"), frames, fps, size,
            scene.camera.name, props.method, props.quality, props.denoise, env,
            spp=props.spp)
        n = frames[1] - frames[0] + 1
        self.update_stats("Chronolux", "rendering %d frame(s)" % n)

        def on_line(line, fraction):
            print("chronolux:", line)
            if fraction is not None:
                self.update_progress(fraction)
                self.update_stats("Chronolux", line[:120])

        runner.run(cmd, self.test_break, on_line)

    def _load(self, out, frame, size):
        path = os.path.join(out, "frame_%04d.exr" % frame)
        if not os.path.isfile(path):
            raise runner.RunError("the run wrote no %s" % path)
        w, h, ch = exr.read(path)
        if (w, h) != size:
            raise runner.RunError("%s is %dx%d, not %dx%d" % (path, w, h, size[0], size[1]))
        for name, chans, _ in PASSES:
            self.add_pass(name, len(chans), chans)
        result = self.begin_result(0, 0, w, h)
        try:
            layer = result.layers[0]

            def put(pass_name, planes):
                p = layer.passes.find_by_name(pass_name, "")
                if p is None:
                    return
                # Blender's rows go bottom up.
                data = np.stack([pl[::-1] for pl in planes], axis=-1).astype(np.float32)
                p.rect.foreach_set(data.ravel())

            alpha = ch.get("A", np.ones((h, w), dtype=np.float32))
            put("Combined", [ch["R"], ch["G"], ch["B"], alpha])
            for name, chans, _ in PASSES:
                planes = [ch.get("ViewLayer.%s.%s" % (name, c)) for c in chans]
                if all(pl is not None for pl in planes):
                    put(name, planes)
        finally:
            self.end_result(result)
