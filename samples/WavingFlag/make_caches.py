"""Regenerate the WavingFlag vertex-cache samples (deterministic; no randomness, no user preferences).

    blender -b --factory-startup --python samples/WavingFlag/make_caches.py

Written for Blender 3.4.1 (Debian 12 package). Builds a 13 x 9 vertex quad grid ("Flag", 117 vertices,
96 quads, one UV map, smooth shading) standing in Blender's XZ plane, animates it with three shape keys
keyed on every frame 1..24 at 24 fps, and exports, next to this script:

    flag.glb                     glTF binary, shape keys as morph targets + weights animation (Y-up, glTF default)
    flag.obj                     the mesh at frame 1, Blender axes (forward Y, up Z: coordinates as in Blender)
    flag.mdd                     io_shape_mdd, frames 1..24, fps 24, no rest frame (Blender axes, world space)
    flag.pc2                     io_export_pc2, frames 1..24, rot_x90 off, world space (Blender axes)
    obj_sequence/flag_NNNN.obj   one OBJ per frame 1..24, same settings as flag.obj

Everything but flag.glb is in Blender's own axes (x, y, z), Z up; flag.glb holds (x, z, -y).
"""

import math
import os
import sys

import addon_utils
import bpy

FPS = 24
FIRST, LAST = 1, 24
NX, NZ = 13, 9            # vertices along the flag's width (X) and height (Z)
WIDTH, HEIGHT = 2.4, 1.6  # metres; the pole side is x = 0
WAVELENGTH = 1.6
AMPLITUDE = 0.15          # at the free edge; grows linearly from 0 at the pole
DROOP = 0.10              # how far the free edge's corners sag at full 'Droop'


def out_dir():
    here = globals().get("__file__")
    if here and os.path.isfile(here):
        return os.path.dirname(os.path.abspath(here))
    # Fallback: the path that follows --python on the command line.
    argv = sys.argv
    for i, a in enumerate(argv[:-1]):
        if a in ("--python", "-P"):
            return os.path.dirname(os.path.abspath(argv[i + 1]))
    raise RuntimeError("cannot tell where make_caches.py lives")


def phase(frame):
    """One full wave period over frames 1..24, so frame 25 would equal frame 1 (a seamless loop)."""
    return 2.0 * math.pi * (frame - FIRST) / (LAST - FIRST + 1)


def key_values(frame):
    p = phase(frame)
    # WaveSin * cos(p) - WaveCos * sin(p) = a(x) * sin(k x - p): a wave travelling towards +X.
    return {"WaveSin": math.cos(p), "WaveCos": -math.sin(p), "Droop": 0.5 + 0.5 * math.sin(p)}


def build_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    for name in ("io_shape_mdd", "io_export_pc2"):
        addon_utils.enable(name, default_set=True)

    scene = bpy.context.scene
    scene.render.fps = FPS
    scene.render.fps_base = 1.0
    scene.frame_start = FIRST
    scene.frame_end = LAST

    # Vertex i + NX * j sits at (i * dx, 0, j * dz): rows of constant height, pole side first.
    dx, dz = WIDTH / (NX - 1), HEIGHT / (NZ - 1)
    verts = [(i * dx, 0.0, j * dz) for j in range(NZ) for i in range(NX)]
    faces = []
    for j in range(NZ - 1):
        for i in range(NX - 1):
            a = i + NX * j
            faces.append((a, a + 1, a + 1 + NX, a + NX))  # counter-clockwise seen from -Y: normal -Y
    mesh = bpy.data.meshes.new("Flag")
    mesh.from_pydata(verts, [], faces)
    uv = mesh.uv_layers.new(name="UVMap")
    for loop in mesh.loops:
        i, j = loop.vertex_index % NX, loop.vertex_index // NX
        uv.data[loop.index].uv = (i / (NX - 1), j / (NZ - 1))
    for poly in mesh.polygons:
        poly.use_smooth = True
    mesh.validate()
    mesh.update()

    obj = bpy.data.objects.new("Flag", mesh)
    scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)

    k = 2.0 * math.pi / WAVELENGTH
    obj.shape_key_add(name="Basis", from_mix=False)
    shapes = {
        "WaveSin": lambda x, z: (0.0, AMPLITUDE * (x / WIDTH) * math.sin(k * x), 0.0),
        "WaveCos": lambda x, z: (0.0, AMPLITUDE * (x / WIDTH) * math.cos(k * x), 0.0),
        "Droop": lambda x, z: (0.0, 0.0, -DROOP * (x / WIDTH) ** 2),
    }
    for name, offset in shapes.items():
        key = obj.shape_key_add(name=name, from_mix=False)
        key.slider_min = -1.0
        key.slider_max = 1.0
        for n, (x, y, z) in enumerate(verts):
            ox, oy, oz = offset(x, z)
            key.data[n].co = (x + ox, y + oy, z + oz)

    blocks = mesh.shape_keys.key_blocks
    for frame in range(FIRST, LAST + 1):
        for name, value in key_values(frame).items():
            blocks[name].value = value
            blocks[name].keyframe_insert("value", frame=frame)
    for fcurve in mesh.shape_keys.animation_data.action.fcurves:
        for point in fcurve.keyframe_points:
            point.interpolation = 'LINEAR'
    mesh.shape_keys.animation_data.action.name = "Wave"

    scene.frame_set(FIRST)
    return scene, obj


OBJ_SETTINGS = dict(
    forward_axis='Y', up_axis='Z',  # Blender's own axes: coordinates written as they are in Blender
    global_scale=1.0,
    apply_modifiers=True, export_eval_mode='DAG_EVAL_VIEWPORT',
    export_selected_objects=True,
    export_uv=True, export_normals=True, export_colors=False,
    export_materials=False, export_triangulated_mesh=False,
    export_object_groups=False, export_material_groups=False,
    export_vertex_groups=False, export_smooth_groups=False,
)


def export_all(scene, directory):
    os.makedirs(os.path.join(directory, "obj_sequence"), exist_ok=True)

    scene.frame_set(FIRST)
    bpy.ops.export_scene.gltf(
        filepath=os.path.join(directory, "flag.glb"), export_format='GLB',
        use_selection=False, export_materials='NONE', export_colors=False,
        export_texcoords=True, export_normals=True, export_tangents=False,
        export_cameras=False, export_lights=False, export_extras=False,
        export_yup=True, export_apply=False,
        export_animations=True, export_frame_range=True, export_frame_step=1,
        export_force_sampling=True, export_nla_strips=True,
        export_optimize_animation_size=False, export_current_frame=False,
        export_morph=True, export_morph_normal=True, export_morph_tangent=False)

    scene.frame_set(FIRST)
    bpy.ops.wm.obj_export(filepath=os.path.join(directory, "flag.obj"), export_animation=False,
                          **OBJ_SETTINGS)

    for frame in range(FIRST, LAST + 1):
        scene.frame_set(frame)
        bpy.ops.wm.obj_export(
            filepath=os.path.join(directory, "obj_sequence", "flag_%04d.obj" % frame),
            export_animation=False, **OBJ_SETTINGS)

    scene.frame_set(FIRST)
    bpy.ops.export_shape.mdd(filepath=os.path.join(directory, "flag.mdd"),
                             fps=float(FPS), frame_start=FIRST, frame_end=LAST, use_rest_frame=False)

    scene.frame_set(FIRST)
    bpy.ops.export_shape.pc2(filepath=os.path.join(directory, "flag.pc2"),
                             rot_x90=False, world_space=True, apply_modifiers=True,
                             range_start=FIRST, range_end=LAST, sampling='1')
    scene.frame_set(FIRST)


if __name__ == "__main__":
    directory = out_dir()
    scene, obj = build_scene()
    export_all(scene, directory)
    print("WavingFlag: %d vertices, %d faces, frames %d..%d at %d fps, written to %s"
          % (len(obj.data.vertices), len(obj.data.polygons), FIRST, LAST, FPS, directory))
