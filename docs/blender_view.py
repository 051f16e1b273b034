"""Render a .glb written by `solidtex export` in Blender, from the camera `solidtex view` uses.

    blender -b --python docs/blender_view.py -- MODEL.glb OUT.png [YAW PITCH SIZE]

YAW and PITCH are degrees as in `solidtex view` (default 35 and 25), SIZE the picture's
side in pixels (default 512). Cycles on the CPU, 16 samples, one sun over the viewer's
shoulder; it prints each mesh Blender imported with its vertex and face counts, colour
attributes and materials.
"""
import math
import sys

import bpy
import mathutils
import numpy

if not hasattr(numpy, "bool"):
    numpy.bool = bool  # Debian 12: Blender 3.4's glTF importer uses an alias numpy 1.24 removed

argv = sys.argv[sys.argv.index("--") + 1:]
glb, out = argv[0], argv[1]
yaw = math.radians(float(argv[2]) if len(argv) > 2 else 35.0)
pitch = math.radians(float(argv[3]) if len(argv) > 3 else 25.0)
size = int(argv[4]) if len(argv) > 4 else 512

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)
meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
for o in meshes:
    me = o.data
    print("IMPORTED", o.name, len(me.vertices), "vertices", len(me.polygons), "faces",
          "colour attributes:", [a.name for a in me.color_attributes],
          "materials:", [m.name for m in me.materials])

scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.samples = 16
scene.cycles.device = "CPU"
scene.cycles.use_denoising = False  # Debian's Blender is built without OpenImageDenoise
scene.render.resolution_x = scene.render.resolution_y = size
world = bpy.data.worlds.new("world")
scene.world = world
world.use_nodes = True
world.node_tree.nodes["Background"].inputs[0].default_value = (0.02, 0.02, 0.025, 1)

corners = [o.matrix_world @ mathutils.Vector(c) for o in meshes for c in o.bound_box]
lo = mathutils.Vector([min(p[i] for p in corners) for i in range(3)])
hi = mathutils.Vector([max(p[i] for p in corners) for i in range(3)])
centre, extent = (lo + hi) / 2, (hi - lo).length

# towards the camera, in glTF axes (+y up) as `solidtex view` has it, then in Blender's
# (+z up): the importer turns glTF (x, y, z) into Blender (x, -z, y)
d = mathutils.Vector((math.sin(yaw) * math.cos(pitch), math.sin(pitch), math.cos(yaw) * math.cos(pitch)))
d = mathutils.Vector((d.x, -d.z, d.y))
camera = bpy.data.cameras.new("camera")
camera.type = "ORTHO"
camera.ortho_scale = extent * 0.8
eye = bpy.data.objects.new("camera", camera)
scene.collection.objects.link(eye)
scene.camera = eye
eye.location = centre + d * extent * 2
back = d.normalized()
right = mathutils.Vector((0, 0, 1)).cross(back).normalized()
up = back.cross(right)
eye.rotation_euler = mathutils.Matrix((right, up, back)).transposed().to_euler()

sun = bpy.data.lights.new("sun", "SUN")
sun.energy = 4.0
light = bpy.data.objects.new("sun", sun)
scene.collection.objects.link(light)
light.rotation_euler = (-(d + mathutils.Vector((0.3, 0, 0.6)))).to_track_quat("-Z", "Y").to_euler()

scene.render.image_settings.file_format = "PNG"
scene.render.filepath = out
bpy.ops.render.render(write_still=True)
