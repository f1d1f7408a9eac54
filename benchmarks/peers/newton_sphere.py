"""NVIDIA Newton's VBD cloth solver on the sphere-drop scene, on the CPU, run by
``benchmarks/compare.py`` in its own venv (newton 1.8.0):

    python newton_sphere.py N SELF OUT.npz SECONDS FABRIC_JSON

A 1 m cloth of N x N particles 0.32 m above a static sphere (r = 0.3 m) at the origin, Z up,
SECONDS at 60 frames per second, 10 substeps of 10 VBD iterations (Newton's cloth examples), in
party's fabric (FABRIC_JSON: ``Fabric.to_dict()``, SI units) as far as Newton's isotropic
membrane can carry it (:func:`newton_material`). The first frame (kernel compilation) is timed
apart. Writes the final positions [m] and those two frames before (``points_before``,
``interval`` [s] earlier), the triangles, start-up and wall seconds to OUT.npz.
"""
import json
import sys
import time

import numpy as np

t0 = time.perf_counter()
import newton  # noqa: E402
import warp as wp  # noqa: E402


def newton_material(fabric: dict, spacing: float, particles: int, area: float) -> dict:
    """Newton's cloth parameters for party's ``fabric`` on a grid of ``spacing`` [m] with
    ``particles`` over ``area`` [m^2].

    - ``mass`` per particle: the areal density spread evenly (Newton's grid gives every particle
      the same mass).
    - ``tri_ke``, ``tri_ka``: the Lame parameters (mu, lambda) [N/m] of Newton's stable
      neo-Hookean membrane, isotropic. party's net has its tensile stiffness E along warp and
      weft (their mean here), Poisson's ratio about 0 and a separate, weaker shear modulus; an
      isotropic membrane with lambda 0 has E = 2 mu, so mu = E / 2 keeps the stretch (its shear
      modulus, mu, is then E / 2 where party's is ``shear``).
    - ``edge_ke``: Newton's hinge energy is stiffness L (angle)^2 / 2 over an edge of length L;
      a bending rigidity B spread over the d = 2h/3 between the two triangles' centroids (an
      axis edge of the grid) gives stiffness B / d.
    - ``tri_kd``: Newton's membrane damping is a viscosity on the rate of C = F^T F, which
      doubles both the strain rate and its gradient; party damps each neighbour pair h apart by
      c = damping h^2 [kg/s], a viscosity of c [N s/m] along the pair, so c / 4.
    - ``edge_kd``: Newton's hinge damps by edge_kd L d(angle)/dt; party's pair across the hinge
      by c d^2 d(angle)/dt over its length h, so c d^2 / h.
    - ``mu``: the cloth-body friction coefficient."""
    tensile = 0.5 * (fabric["tensile_warp"] + fabric["tensile_weft"])
    viscous = fabric["damping"] * spacing ** 2
    between = 2.0 * spacing / 3.0
    return {"mass": fabric["areal_density"] * area / particles, "tri_ke": 0.5 * tensile, "tri_ka": 0.0,
            "tri_kd": 0.25 * viscous, "edge_ke": fabric["bending_rigidity"] / between,
            "edge_kd": viscous * between ** 2 / spacing, "mu": fabric["friction"]}


wp.config.quiet = True
n, self_contact, out = int(sys.argv[1]), sys.argv[2] == "1", sys.argv[3]
seconds, fabric = float(sys.argv[4]), json.loads(sys.argv[5])
fps, substeps, iterations = 60, 10, 10
builder = newton.ModelBuilder(up_axis=newton.Axis.Z)
cell = 1.0 / (n - 1)
material = newton_material(fabric, cell, n * n, 1.0)
builder.add_cloth_grid(pos=wp.vec3(-0.5, -0.5, 0.62), rot=wp.quat_identity(), vel=wp.vec3(0.0), dim_x=n - 1,
                       dim_y=n - 1, cell_x=cell, cell_y=cell, mass=material["mass"], tri_ke=material["tri_ke"],
                       tri_ka=material["tri_ka"], tri_kd=material["tri_kd"], edge_ke=material["edge_ke"],
                       edge_kd=material["edge_kd"], particle_radius=0.004)
builder.add_shape_sphere(body=-1, xform=wp.transform(wp.vec3(0.0, 0.0, 0.0), wp.quat_identity()), radius=0.3)
builder.color(include_bending=True)
model = builder.finalize(device="cpu")
model.soft_contact_ke, model.soft_contact_kd, model.soft_contact_mu = 1.0e3, 1.0e-2, material["mu"]
solver = newton.solvers.SolverVBD(model=model, iterations=iterations, particle_enable_self_contact=self_contact,
                                  particle_self_contact_margin=0.008, particle_self_contact_gap=0.004)
states = [model.state(), model.state()]
control = model.control()
pipeline = newton.CollisionPipeline(model)
contacts = pipeline.contacts()
dt = 1.0 / fps / substeps


def frame():
    for _ in range(substeps):
        states[0].clear_forces()
        pipeline.collide(states[0], contacts)
        solver.step(states[0], states[1], control, contacts, dt)
        states.reverse()


frame()
wp.synchronize()
setup = time.perf_counter() - t0
t = time.perf_counter()
frames = round(fps * seconds)
before = 2  # frames before the end, 1/30 s, for the final speed (the copy not timed)
reading = 0.0
for k in range(frames - 1):
    if k == frames - 1 - before:
        read = time.perf_counter()
        points_before = states[0].particle_q.numpy().copy()
        reading = time.perf_counter() - read
    frame()
wp.synchronize()
wall = (time.perf_counter() - t - reading) * frames / (frames - 1)
np.savez(out, points=states[0].particle_q.numpy(), triangles=model.tri_indices.numpy(), setup_seconds=setup,
         wall_seconds=wall, simulated_seconds=frames / fps, points_before=points_before, interval=before / fps)
