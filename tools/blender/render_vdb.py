"""Blender (headless) imports natscene's density.vdb as a volume object and renders it with Cycles.

    blender -b --factory-startup --python tools/blender/render_vdb.py -- density.vdb out.png [size]

natscene's world is y-up metres; Blender's is z-up: the object is rotated +90 degrees about x. The camera looks
at the object's bounding box from the front (natscene -z = Blender +y side... i.e. from -y in Blender after the
rotation) with a sun from the side; Principled Volume (density 1 x grid, scaled by 1 / voxel so that a few
voxels of density 1 are opaque), black world (so the sky stays 0), Standard view transform. Prints the grid names Blender found.
"""
import math
import sys

import bpy
from mathutils import Vector

argv = sys.argv[sys.argv.index("--") + 1:]
vdb_path, out_png = argv[0], argv[1]
size = int(argv[2]) if len(argv) > 2 else 96

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 16
scene.cycles.use_denoising = False
scene.view_layers[0].cycles.denoising_store_passes = False
scene.cycles.volume_bounces = 2
scene.render.resolution_x = size
scene.render.resolution_y = size
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "PNG"
scene.render.filepath = out_png

bpy.ops.object.volume_import(filepath=vdb_path, align="WORLD", location=(0, 0, 0))
obj = bpy.context.active_object
vol = obj.data
vol.grids.load()
names = [g.name for g in vol.grids]
print("NATSCENE_GRIDS", names)
obj.rotation_euler = (math.radians(90), 0, 0)        # y-up metres -> Blender z-up
bpy.context.view_layer.update()

corners = [obj.matrix_world @ Vector(c) for c in obj.bound_box]
lo = Vector([min(c[i] for c in corners) for i in range(3)])
hi = Vector([max(c[i] for c in corners) for i in range(3)])
centre, ext = (lo + hi) / 2, hi - lo
print("NATSCENE_BBOX", tuple(lo), tuple(hi))

mat = bpy.data.materials.new("cloud")
mat.use_nodes = True
nt = mat.node_tree
for n in list(nt.nodes):
    nt.nodes.remove(n)
out = nt.nodes.new("ShaderNodeOutputMaterial")
pv = nt.nodes.new("ShaderNodeVolumePrincipled")
voxel = max(ext) / 100.0
pv.inputs["Density"].default_value = 8.0 / max(max(ext) / 64.0, 1e-9)   # ~8 optical depths per 64th of the box
pv.inputs["Color"].default_value = (1, 1, 1, 1)
nt.links.new(pv.outputs["Volume"], out.inputs["Volume"])
vol.materials.append(mat)

world = bpy.data.worlds.new("sky")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1)
scene.view_settings.view_transform = "Standard"
scene.world = world

sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", type="SUN"))
sun.data.energy = 4.0
sun.rotation_euler = (math.radians(60), math.radians(40), 0)
scene.collection.objects.link(sun)

cam_data = bpy.data.cameras.new("cam")
cam = bpy.data.objects.new("cam", cam_data)
scene.collection.objects.link(cam)
scene.camera = cam
dist = 3.0 * max(ext)
cam.location = centre + Vector((0, -dist, 0))
direction = centre - cam.location
cam.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
cam_data.angle = 2 * math.atan(0.6 * max(ext[0], ext[2]) / (dist - ext[1] / 2))
cam_data.clip_end = 10 * dist
bpy.ops.render.render(write_still=True)
print("NATSCENE_RENDERED", out_png)
