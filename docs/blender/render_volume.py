# Render a solidtex OpenVDB volume in Blender with a Principled Volume shader.
#
#   solidtex convert out/kiwi.exr kiwi.vdb
#   blender --background --factory-startup --python docs/blender/render_volume.py -- kiwi.vdb kiwi.png [DENSITY]
#
# The file's `density` grid (the exemplar's alpha, or 1 inside) scales the Density input
# (DENSITY, default 40: nearly opaque, so the faces show the exemplar's outer slices) and
# its `color` grid (an Attribute node) drives the Color and Emission Color. Cycles on the CPU, 480x360, 32 samples.
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
if len(args) < 2:
    sys.exit("usage: blender --background --python render_volume.py -- VOLUME.vdb OUT.png [DENSITY]")
vdb, picture = args[0], args[1]
density = float(args[2]) if len(args) > 2 else 40.0

scene = bpy.context.scene
for obj in list(scene.objects):
    bpy.data.objects.remove(obj, do_unlink=True)

bpy.ops.object.volume_import(filepath=vdb, align="WORLD", location=(0, 0, 0))
volume = bpy.context.active_object
volume.location = (-0.5, -0.5, -0.5)  # solidtex volumes span [0, 1] along their longest side

material = bpy.data.materials.new("solidtex")
material.use_nodes = True
nodes = material.node_tree.nodes
nodes.clear()
shader = nodes.new("ShaderNodeVolumePrincipled")
shader.inputs["Density"].default_value = density
shader.inputs["Density Attribute"].default_value = "density"
# The colour grid both scatters and glows a little, so the exemplar's colours read as they
# are rather than darkened by many scattering bounces.
colour = nodes.new("ShaderNodeAttribute")
colour.attribute_name = "color"
links = material.node_tree.links
links.new(colour.outputs["Color"], shader.inputs["Color"])
links.new(colour.outputs["Color"], shader.inputs["Emission Color"])
shader.inputs["Emission Strength"].default_value = 0.8
output = nodes.new("ShaderNodeOutputMaterial")
links.new(shader.outputs["Volume"], output.inputs["Volume"])
volume.data.materials.append(material)

bpy.ops.object.camera_add(location=(1.9, -1.6, 1.4))
camera = bpy.context.active_object
direction = -camera.location
camera.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
scene.camera = camera

bpy.ops.object.light_add(type="SUN", location=(2, -1, 3))
bpy.context.active_object.data.energy = 4.0
world = bpy.data.worlds.new("grey") if scene.world is None else scene.world
scene.world = world
world.use_nodes = True
world.color = (0.09, 0.09, 0.1)
world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.09, 0.09, 0.1, 1)
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.3

scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 32
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = 480, 360
scene.render.filepath = picture
bpy.ops.render.render(write_still=True)
