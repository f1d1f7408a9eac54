"""Blender's cloth on the sphere-drop scene, run by ``benchmarks/compare.py`` in its own venv
(bpy 5.0.1, Python 3.11):

    python blender_sphere.py -- N SELF OUT.npz SECONDS FABRIC_JSON

A 1 m cloth of N x N vertices 0.32 m above a static sphere (r = 0.3 m) at the origin, Z up,
SECONDS at 30 frames per second, quality 5, in party's fabric (FABRIC_JSON: ``Fabric.to_dict()``,
SI units) as far as Blender's mass-spring model can carry it (:func:`blender_material`).
Blender keeps cloth its own distance plus the collision object's outer thickness off a body
(its default thickness, 0.02 m, held the cloth 19 mm off the sphere, where party's and Newton's
rest about 3 mm off it), so the sphere gets Blender's thinnest, 1 mm, and the cloth 3 mm of
its own and :data:`COLLISION_QUALITY` collision passes a step. Writes the final vertex positions
[m] and those a frame before (``points_before``, ``interval`` [s] earlier), the set-up seconds
and the simulation wall seconds to OUT.npz, with the grid's quads split into triangles.
"""
import json
import math
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

FPS = 30
"""The scene's frames per second."""

TIME_UNIT = math.sqrt(1.0e-3)
"""Blender's cloth time unit [s]: its solver scales gravity by 0.001 (``cloth_calc_force``), so
gravity is true where one unit is sqrt(0.001) s. A frame advances ``time_scale`` units; with
its default, 1, a frame of a 30 fps scene is 0.0316 s and the cloth falls at 0.9 g (a free
fall of 1 s: 4.44 m; with ``time_scale`` 1 / (30 fps * TIME_UNIT), 4.94 m, implicit Euler's
4.905 * (1 + dt))."""


def blender_material(fabric: dict, spacing: float, vertices: int, area: float) -> dict:
    """Blender cloth settings for party's ``fabric`` on a square grid of ``spacing`` [m]
    (Blender's average spring length) with ``vertices`` over ``area`` [m^2]. Blender's forces
    are in kg m / unit^2 (unit: :data:`TIME_UNIT`), so a stiffness of K [N/m] is K u^2 [kg/unit^2]
    and a damping coefficient c [kg/s] is c u [kg/unit].

    - ``mass``: per vertex, the areal density spread evenly (Blender gives every vertex the
      same mass).
    - ``tension``: Blender's structural spring is tension / spacing; party's warp or weft
      element is tensile * width / length, the tensile stiffness itself on a square grid (their
      mean). A strip of 11 x 41 vertices 25 mm apart, of a tenth of cotton's tensile stiffness
      and no shear, hanging from its top row stretched 25.67 mm in Blender, what the discrete
      chain gives to four digits. ``compression``: the same, which Blender's
      angular model spends on Choi and Ko's buckling response instead of a linear spring.
    - ``shear``: both diagonals of each quad, shear / spacing each: a net of diagonals of
      stiffness k has shear modulus k.
    - ``bending``: Blender's angular spring puts k (angle - rest) on each face across an edge of
      length L, k = bending L / 10; the moment k angle h about the edge against a curvature of
      angle / h over that length, B L angle / h, gives bending = 10 B u^2 / h^2. (Not checked
      against a cantilever: Blender's strips of these masses twisted and did not settle.)
    - dampers: party damps each neighbour pair by damping * h^2 [kg/s] (its viscous term);
      Blender's springs damp along themselves by their damping [kg/unit].
    - ``air_damping`` 0: party's scene has no air.
    - ``time_scale``: a frame is 1 / :data:`FPS` s (:data:`TIME_UNIT`).

    The sphere's friction, set on its collision settings, is mu * 100: Blender's friction cuts
    the tangential velocity by 0.01 friction times the normal one."""
    u2 = TIME_UNIT ** 2
    damper = fabric["damping"] * spacing ** 2 * TIME_UNIT
    tensile = 0.5 * (fabric["tensile_warp"] + fabric["tensile_weft"])
    return {"mass": fabric["areal_density"] * area / vertices, "air_damping": 0.0,
            "tension_stiffness": tensile * u2 * spacing, "compression_stiffness": tensile * u2 * spacing,
            "shear_stiffness": fabric["shear"] * u2 * spacing,
            "bending_stiffness": 10.0 * fabric["bending_rigidity"] * u2 / spacing ** 2,
            "tension_damping": damper, "compression_damping": damper, "shear_damping": damper,
            "bending_damping": damper, "time_scale": 1.0 / (FPS * TIME_UNIT)}


args = sys.argv[sys.argv.index("--") + 1:]
n, self_collision, out = int(args[0]), args[1] == "1", args[2]
seconds, fabric = float(args[3]), json.loads(args[4])
last = 1 + round(FPS * seconds)
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.frame_start, scene.frame_end, scene.render.fps = 1, last, FPS
bpy.ops.mesh.primitive_grid_add(x_subdivisions=n - 1, y_subdivisions=n - 1, size=1.0, location=(0, 0, 0.62))
cloth = bpy.context.active_object
bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=0.3, location=(0, 0, 0))
sphere = bpy.context.active_object
sphere.modifiers.new("collision", "COLLISION")
sphere.collision.cloth_friction = 100.0 * fabric["friction"]
sphere.collision.thickness_outer = OUTER_THICKNESS
modifier = cloth.modifiers.new("cloth", "CLOTH")
for name, value in blender_material(fabric, 1.0 / (n - 1), n * n, 1.0).items():
    setattr(modifier.settings, name, value)
modifier.settings.quality = 5
modifier.collision_settings.collision_quality = COLLISION_QUALITY
modifier.collision_settings.use_self_collision = self_collision
modifier.collision_settings.distance_min = DISTANCE - OUTER_THICKNESS
modifier.collision_settings.self_distance_min = DISTANCE
modifier.point_cache.frame_end = last


def cloth_points() -> np.ndarray:
    """The cloth's vertices at the current frame, in world space [m]."""
    evaluated = cloth.evaluated_get(bpy.context.evaluated_depsgraph_get())
    return np.array([(evaluated.matrix_world @ v.co)[:] for v in evaluated.data.vertices])


setup = time.perf_counter() - t0
t = time.perf_counter()
reading = 0.0
for frame in range(1, last + 1):
    scene.frame_set(frame)
    if frame == last - 1:  # a frame before the end, for the final speed (its reading not timed)
        read = time.perf_counter()
        points_before = cloth_points()
        reading = time.perf_counter() - read
wall = time.perf_counter() - t - reading
points = cloth_points()
evaluated = cloth.evaluated_get(bpy.context.evaluated_depsgraph_get())
quads = np.array([tuple(p.vertices) for p in evaluated.data.polygons])
triangles = np.r_[quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]
np.savez(out, points=points, triangles=triangles, setup_seconds=setup, wall_seconds=wall,
         simulated_seconds=(last - 1) / FPS, points_before=points_before, interval=1.0 / FPS)
