"""Blender's cloth on the sphere-drop scene, run by ``benchmarks/compare.py`` in its own venv
(bpy 5.0.1, Python 3.11):

    python blender_sphere.py -- N SELF OUT.npz [SECONDS]

A 1 m cloth of N x N vertices 0.32 m above a static sphere (r = 0.3 m) at the origin, Z up,
SECONDS (default 1) at 30 frames per second, quality 5, collision distance 4 mm (Blender's
defaults otherwise, a cotton-like cloth). Blender keeps cloth its own distance plus the collision
object's outer thickness off a body (its default thickness, 0.02 m, held the cloth 19 mm off the
sphere, where party's and Newton's rest about 3 mm off it), so the sphere gets Blender's thinnest,
1 mm, and the cloth 3 mm of its own and :data:`COLLISION_QUALITY` collision passes a step.
Writes the final vertex positions [m], the set-up seconds and the simulation wall seconds to
OUT.npz, with the grid's quads split into triangles.
"""
import sys
import time

import numpy as np

t0 = time.perf_counter()
import bpy  # noqa: E402

DISTANCE = 0.004
"""How far Blender keeps the cloth off the sphere [m] (its distance plus the sphere's outer thickness)."""
OUTER_THICKNESS = 0.001
COLLISION_QUALITY = 4
"""Blender's collision passes per step: the fewest that hold the cloth on the sphere at this
distance (with its default, 2, and with 3 the cloth fell through)."""

args = sys.argv[sys.argv.index("--") + 1:]
n, self_collision, out = int(args[0]), args[1] == "1", args[2]
seconds = float(args[3]) if len(args) > 3 else 1.0
last = 1 + round(30 * seconds)
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.frame_start, scene.frame_end, scene.render.fps = 1, last, 30
bpy.ops.mesh.primitive_grid_add(x_subdivisions=n - 1, y_subdivisions=n - 1, size=1.0, location=(0, 0, 0.62))
cloth = bpy.context.active_object
bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=0.3, location=(0, 0, 0))
sphere = bpy.context.active_object
sphere.modifiers.new("collision", "COLLISION")
sphere.collision.cloth_friction = 5.0
sphere.collision.thickness_outer = OUTER_THICKNESS
modifier = cloth.modifiers.new("cloth", "CLOTH")
modifier.settings.quality = 5
modifier.collision_settings.collision_quality = COLLISION_QUALITY
modifier.collision_settings.use_self_collision = self_collision
modifier.collision_settings.distance_min = DISTANCE - OUTER_THICKNESS
modifier.collision_settings.self_distance_min = DISTANCE
modifier.point_cache.frame_end = last
setup = time.perf_counter() - t0
t = time.perf_counter()
for frame in range(1, last + 1):
    scene.frame_set(frame)
wall = time.perf_counter() - t
evaluated = cloth.evaluated_get(bpy.context.evaluated_depsgraph_get())
points = np.array([(evaluated.matrix_world @ v.co)[:] for v in evaluated.data.vertices])
quads = np.array([tuple(p.vertices) for p in evaluated.data.polygons])
triangles = np.r_[quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]
np.savez(out, points=points, triangles=triangles, setup_seconds=setup, wall_seconds=wall,
         simulated_seconds=(last - 1) / 30)
