"""Chronolux for Blender: a render engine that exports the scene to glTF with Blender's own
exporter, passes the world's environment texture, runs the `chronolux` binary (one temporal
run for an animation) and loads its EXR frames and passes into the render result."""

bl_info = {
    "name": "Chronolux",
    "author": "Chronolux developers",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "Properties > Render > Render Engine > Chronolux",
    "description": "Temporal global-illumination renderer for animations",
    "category": "Render",
}

import bpy

from . import engine

METHODS = (
    ("spacetime-dept", "spacetime-dept", "Space-time photon density estimation (the default)"),
    ("stbpt", "stbpt", "Spatio-temporal bidirectional path tracing (unbiased)"),
    ("path", "path", "Frame-by-frame path tracing (the reference)"),
    ("bdpt", "bdpt", "Frame-by-frame bidirectional path tracing"),
    ("spt", "spt", "Selective photon tracing"),
    ("dept", "dept", "Frame-by-frame photon density estimation"),
    ("dept-spatial", "dept-spatial", "dept with a spatial Gaussian filter"),
    ("dept-bilateral", "dept-bilateral", "dept with a spatial bilateral filter"),
    ("ic-static-dynamic", "ic-static-dynamic", "Photon mapping with static and dynamic irradiance caches"),
    ("ic-selective", "ic-selective", "Selective irradiance-cache update"),
    ("pm-ic", "pm-ic", "Frame-by-frame photon mapping with an irradiance cache"),
)


class ChronoluxPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    binary_path: bpy.props.StringProperty(
        name="Chronolux binary",
        description="Path of the chronolux executable (target/release/chronolux); empty: "
        "$CHRONOLUX_BINARY, then chronolux on PATH",
        subtype="FILE_PATH",
        default="",
    )

    def draw(self, context):
        self.layout.prop(self, "binary_path")


class ChronoluxSceneSettings(bpy.types.PropertyGroup):
    method: bpy.props.EnumProperty(name="Method", items=METHODS, default="spacetime-dept",
                                   description="Light-transport method (chronolux render --method)")
    quality: bpy.props.EnumProperty(
        name="Quality",
        items=(("draft", "Draft", "About HDR-FLIP 0.10 on the shared Cornell scenes"),
               ("preview", "Preview", "About HDR-FLIP 0.08 (the default)"),
               ("final", "Final", "About HDR-FLIP 0.06")),
        default="preview",
        description="Effort level (--quality; methods without a quality table use their defaults)")
    denoise: bpy.props.BoolProperty(name="Denoise", default=True,
                                    description="Denoise with Open Image Denoise (--denoise / --no-denoise)")
    spp: bpy.props.IntProperty(name="Samples", default=0, min=0, max=1048576,
                               description="Camera samples per pixel (--spp); 0: the quality level's")


class CHRONOLUX_PT_render(bpy.types.Panel):
    bl_label = "Chronolux"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {"CHRONOLUX"}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        s = context.scene.chronolux
        col = self.layout.column()
        col.use_property_split = True
        col.prop(s, "method")
        col.prop(s, "quality")
        col.prop(s, "denoise")
        col.prop(s, "spp")


def _builtin_panels():
    """Blender's own panels that make sense for Chronolux: output, format and frame range,
    camera, light and world data, colour management; those that show for Eevee or Cycles.
    Not the engines' own sampling or pass panels."""
    import bl_ui

    engines = {"BLENDER_EEVEE", "BLENDER_EEVEE_NEXT", "CYCLES", "BLENDER_WORKBENCH"}
    for mod_name in ("properties_output", "properties_data_camera", "properties_data_light",
                     "properties_world", "properties_render"):
        mod = getattr(bl_ui, mod_name, None)
        if mod is None:
            continue
        for name in dir(mod):
            if mod_name == "properties_render" and "color_management" not in name.lower():
                continue
            p = getattr(mod, name)
            compat = getattr(p, "COMPAT_ENGINES", None)
            if isinstance(compat, set) and compat & engines:
                yield p


CLASSES = (ChronoluxPreferences, ChronoluxSceneSettings, CHRONOLUX_PT_render,
           engine.ChronoluxRenderEngine)


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)
    bpy.types.Scene.chronolux = bpy.props.PointerProperty(type=ChronoluxSceneSettings)
    for p in _builtin_panels():
        p.COMPAT_ENGINES.add("CHRONOLUX")
    for h in (bpy.app.handlers.render_complete, bpy.app.handlers.render_cancel):
        if engine._clear_animation not in h:
            h.append(engine._clear_animation)


def unregister():
    for h in (bpy.app.handlers.render_complete, bpy.app.handlers.render_cancel):
        if engine._clear_animation in h:
            h.remove(engine._clear_animation)
    for p in _builtin_panels():
        p.COMPAT_ENGINES.discard("CHRONOLUX")
    del bpy.types.Scene.chronolux
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
