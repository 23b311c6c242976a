"""Scene export for Chronolux: the scene through Blender's own glTF exporter, area lights as
emissive quads (glTF has no area light; the exporter skips them), and the world's light as
an equirectangular map for ``--environment``."""

import math
import os

import bpy


class ExportError(Exception):
    """Something the add-on cannot export: shown in Blender's UI as an error."""


ENV_EXTENSIONS = (".exr", ".hdr")


def _linked_node(socket):
    if socket is None or not socket.is_linked:
        return None
    return socket.links[0].from_node


def _write_constant_map(color, folder):
    """A 2x1 Radiance HDR of one colour: a uniform world becomes a (constant) map."""
    from . import hdr

    path = os.path.join(folder, "world_color.hdr")
    hdr.write(path, 2, 1, [tuple(color[:3])] * 2)
    return path


def _image_file(image, folder):
    """A file Chronolux reads for a Blender image: the image's own .exr/.hdr when it is one
    on disk, else a linear float copy written as OpenEXR into ``folder``."""
    if image.source == "FILE" and not image.packed_file:
        path = bpy.path.abspath(image.filepath, library=image.library)
        if os.path.splitext(path)[1].lower() in ENV_EXTENSIONS and os.path.isfile(path):
            return path
    w, h = image.size
    if w == 0 or h == 0:
        raise ExportError(
            "the world's Environment Texture image '%s' has no pixels (missing file?)" % image.name
        )
    copy = bpy.data.images.new("chronolux_env_copy", w, h, float_buffer=True, alpha=True)
    try:
        # A float image holds scene-linear values and is saved as such.
        copy.pixels.foreach_set(_pixels(image))
        path = os.path.join(folder, "world_env.exr")
        copy.filepath_raw = path
        copy.file_format = "OPEN_EXR"
        copy.save()
    finally:
        bpy.data.images.remove(copy)
    return path


def _pixels(image):
    import numpy as np

    px = np.empty(image.size[0] * image.size[1] * image.channels, dtype=np.float32)
    image.pixels.foreach_get(px)
    if image.channels != 4:
        px = px.reshape(-1, image.channels)
        rgba = np.ones((px.shape[0], 4), dtype=np.float32)
        rgba[:, : min(3, image.channels)] = px[:, :3]
        px = rgba.ravel()
    return px


def world_environment(scene, folder, warn):
    """(file, strength, rotation in degrees) of the world's light, or None for no world.

    Read from the World's node tree: World Output ← Background (its Strength) ← Environment
    Texture (its image) ← optionally a Mapping node (its Z rotation; type Point as is, type
    Texture inverted). A Background with a constant colour becomes a constant map. Other
    setups (sky textures, mixes) are reported through ``warn`` and export no world."""
    world = scene.world
    if world is None:
        return None
    if not world.use_nodes or world.node_tree is None:
        return (_write_constant_map(world.color, folder), 1.0, 0.0)
    nodes = world.node_tree.nodes
    outputs = [n for n in nodes if n.type == "OUTPUT_WORLD"]
    out = next((n for n in outputs if n.is_active_output), outputs[0] if outputs else None)
    if out is None:
        return None
    bg = _linked_node(out.inputs.get("Surface"))
    if bg is None:
        return None
    if bg.type != "BACKGROUND":
        warn("world: the World Output is fed by a '%s' node, not a Background: no world light exported" % bg.name)
        return None
    strength_in = bg.inputs["Strength"]
    if strength_in.is_linked:
        warn("world: the Background's Strength is driven by a node: using its value %.3g" % strength_in.default_value)
    strength = float(strength_in.default_value)
    color_in = bg.inputs["Color"]
    tex = _linked_node(color_in)
    if tex is None:
        return (_write_constant_map(color_in.default_value, folder), strength, 0.0)
    if tex.type != "TEX_ENVIRONMENT":
        warn("world: the Background's Color comes from a '%s' node (only an Environment Texture is exported): no world light exported" % tex.name)
        return None
    if tex.image is None:
        raise ExportError("the world's Environment Texture has no image")
    if tex.projection != "EQUIRECTANGULAR":
        raise ExportError("the world's Environment Texture uses %s projection; Chronolux reads equirectangular maps" % tex.projection.lower())
    rotation = 0.0
    mapping = _linked_node(tex.inputs.get("Vector"))
    if mapping is not None and mapping.type == "MAPPING":
        rot = mapping.inputs["Rotation"].default_value
        if abs(rot[0]) > 1e-6 or abs(rot[1]) > 1e-6:
            warn("world: the Mapping node's X/Y rotation is not exported (only Z, about the up axis)")
        rotation = math.degrees(rot[2])
        if mapping.vector_type == "TEXTURE":
            rotation = -rotation
    elif mapping is not None and mapping.type != "TEX_COORD":
        warn("world: the Environment Texture's Vector comes from a '%s' node: ignored" % mapping.name)
    return (_image_file(tex.image, folder), strength, rotation)


def _is_animated(obj):
    o = obj
    while o is not None:
        ad = o.animation_data
        if ad is not None and (ad.action is not None or len(ad.drivers) or len(ad.nla_tracks)):
            return True
        if o.constraints:
            return True
        o = o.parent
    return False


def area_lights_as_quads(scene, depsgraph, warn):
    """Adds one emissive mesh per visible area light (Cycles' area light radiance
    L = P / (π A), A its area in world units; one-sided, emitting along the light's −Z,
    Lambertian). Returns the objects and meshes/materials created, for removal after
    the export."""
    created = []
    for obj in scene.objects:
        if obj.type != "LIGHT" or obj.data.type != "AREA" or obj.hide_render:
            continue
        if not obj.visible_get():
            continue
        light = obj.data
        if _is_animated(obj):
            warn("area light '%s' is animated: exported where it is on this frame" % obj.name)
        if abs(getattr(light, "spread", math.pi) - math.pi) > 1e-4:
            warn("area light '%s': its spread is not exported (Lambertian emission)" % obj.name)
        sx = light.size / 2
        sy = (light.size_y if light.shape in ("RECTANGLE", "ELLIPSE") else light.size) / 2
        if light.shape in ("DISK", "ELLIPSE"):
            n = 24
            verts = [(sx * math.cos(2 * math.pi * k / n), -sy * math.sin(2 * math.pi * k / n), 0.0) for k in range(n)]
            faces = [list(range(n))]
            area_local = math.pi * sx * sy
        else:
            # Winding so that the face normal is −Z (the light's direction).
            verts = [(-sx, -sy, 0.0), (-sx, sy, 0.0), (sx, sy, 0.0), (sx, -sy, 0.0)]
            faces = [[0, 1, 2, 3]]
            area_local = 4 * sx * sy
        m = obj.matrix_world
        scale = m.to_scale()
        area = area_local * abs(scale[0] * scale[1])
        if area <= 0:
            continue
        radiance = light.energy / (math.pi * area)
        mesh = bpy.data.meshes.new("chronolux_area_" + obj.name)
        mesh.from_pydata(verts, [], faces)
        mesh.update()
        mat = bpy.data.materials.new("chronolux_area_" + obj.name)
        mat.use_nodes = True
        mat.use_backface_culling = True  # one-sided in glTF (doubleSided false)
        bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
        bsdf.inputs["Base Color"].default_value = (0, 0, 0, 1)
        bsdf.inputs["Roughness"].default_value = 1.0
        bsdf.inputs["Emission Color"].default_value = (*light.color[:3], 1.0)
        bsdf.inputs["Emission Strength"].default_value = radiance
        mesh.materials.append(mat)
        quad = bpy.data.objects.new("chronolux_area_" + obj.name, mesh)
        quad.matrix_world = m.copy()
        scene.collection.objects.link(quad)
        created.append((quad, mesh, mat))
    return created


def remove_created(created):
    for quad, mesh, mat in created:
        bpy.data.objects.remove(quad, do_unlink=True)
        bpy.data.meshes.remove(mesh)
        bpy.data.materials.remove(mat)


def export_gltf(scene, depsgraph, folder, warn):
    """Exports the scene as ``scene.glb`` into ``folder`` with Blender's glTF exporter:
    animation over the scene's frame range (sampled, so constraints and drivers bake),
    skins, morph targets, cameras and punctual lights (Blender's watts as W/sr, as Cycles
    means them: the exporter's COMPAT conversion). Returns its path."""
    if scene.camera is None:
        raise ExportError("the scene has no active camera: set one (Scene properties > Camera)")
    path = os.path.join(folder, "scene.glb")
    created = area_lights_as_quads(scene, depsgraph, warn)
    try:
        with bpy.context.temp_override(scene=scene):
            result = bpy.ops.export_scene.gltf(
                filepath=path,
                check_existing=False,
                export_format="GLB",
                use_renderable=True,
                export_cameras=True,
                export_lights=True,
                export_import_convert_lighting_mode="COMPAT",
                export_yup=True,
                export_apply=False,
                export_animations=True,
                export_animation_mode="SCENE",
                export_frame_range=True,
                export_force_sampling=True,
                export_bake_animation=True,
                export_anim_slide_to_zero=False,
                export_skins=True,
                export_morph=True,
                export_morph_animation=True,
                export_optimize_animation_size=False,
            )
    finally:
        remove_created(created)
    if "FINISHED" not in result or not os.path.isfile(path):
        raise ExportError("Blender's glTF exporter did not write the scene")
    return path
