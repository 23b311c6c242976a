"""The test scene, built in bpy: a plane, an animated cube, an area light, an HDRI world
whose equirectangular image this module writes itself (a sky gradient, a ground and a small
bright "sun" off to one side, so that a wrong orientation or rotation of the map shows), a
camera. Frames 1-3 at 64x64."""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from chronolux_blender import hdr  # noqa: E402

SIZE = 64
FRAMES = (1, 3)


def write_hdri(path, w=256, h=128):
    """Sky blue above (brighter near the horizon), brown ground below, a sun of radius
    about 5° at azimuth u = 0.3, elevation 35° (about 1000x the sky: its shadow of the cube is as strong as the area light's)."""
    px = []
    sun_t, sun_u = (90 - 35) / 180.0, 0.3
    for y in range(h):
        t = (y + 0.5) / h
        for x in range(w):
            u = (x + 0.5) / w
            du = min(abs(u - sun_u), 1 - abs(u - sun_u)) * 2 * math.pi * math.sin(t * math.pi)
            dt = (t - sun_t) * math.pi
            if du * du + dt * dt < math.radians(5) ** 2:
                c = (600.0, 560.0, 480.0)
            elif t < 0.5:
                k = 0.5 + t
                c = (0.25 * k, 0.45 * k, 0.9 * k)
            else:
                c = (0.18, 0.14, 0.1)
            px.append(c)
    hdr.write(path, w, h, px)


def principled(name, color, ior_level=0.0):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    b = m.node_tree.nodes["Principled BSDF"]
    b.inputs["Base Color"].default_value = (*color, 1)
    b.inputs["Roughness"].default_value = 1.0
    # No specular layer: a Lambertian surface in Cycles and in the exported glTF
    # (KHR_materials_specular factor 0).
    b.inputs["Specular IOR Level"].default_value = ior_level
    return m


def build(folder, rotation_deg=60.0, strength=0.8):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = SIZE
    sc.render.resolution_percentage = 100
    sc.frame_start, sc.frame_end = FRAMES
    sc.render.fps = 24

    bpy.ops.mesh.primitive_plane_add(size=6.0, location=(0, 0, 0))
    plane = bpy.context.object
    plane.data.materials.append(principled("floor", (0.7, 0.7, 0.7)))

    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(-1.0, 0, 0.5))
    cube = bpy.context.object
    cube.data.materials.append(principled("cube", (0.8, 0.25, 0.2)))
    cube.keyframe_insert("location", frame=FRAMES[0])
    cube.location = (1.0, 0.5, 0.5)
    cube.rotation_euler = (0, 0, math.radians(40))
    cube.keyframe_insert("location", frame=FRAMES[1])
    cube.keyframe_insert("rotation_euler", frame=FRAMES[1])
    cube.rotation_euler = (0, 0, 0)
    cube.keyframe_insert("rotation_euler", frame=FRAMES[0])

    light = bpy.data.lights.new("Area", "AREA")
    light.energy = 150.0
    light.size = 1.0
    lo = bpy.data.objects.new("Area", light)
    lo.location = (0.5, -0.5, 3.0)
    sc.collection.objects.link(lo)

    cam = bpy.data.cameras.new("Camera")
    cam.lens = 30
    co = bpy.data.objects.new("Camera", cam)
    co.location = (5.0, -5.0, 3.5)
    sc.collection.objects.link(co)
    direction = -co.location
    co.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    sc.camera = co

    hdri = os.path.join(folder, "sky.hdr")
    write_hdri(hdri)
    world = bpy.data.worlds.new("World")
    sc.world = world
    world.use_nodes = True
    nt = world.node_tree
    bg = nt.nodes["Background"]
    bg.inputs["Strength"].default_value = strength
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(hdri)
    mapping = nt.nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value[2] = math.radians(rotation_deg)
    coord = nt.nodes.new("ShaderNodeTexCoord")
    nt.links.new(coord.outputs["Generated"], mapping.inputs["Vector"])
    nt.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    nt.links.new(env.outputs["Color"], bg.inputs["Color"])
    sc.view_settings.view_transform = "Standard"
    sc.render.image_settings.file_format = "OPEN_EXR"
    sc.render.image_settings.color_depth = "32"
    sc.render.image_settings.exr_codec = "ZIP"
    return sc
