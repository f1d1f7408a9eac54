"""NVIDIA Newton's VBD cloth solver on the sphere-drop scene, on the CPU, run by
``benchmarks/compare.py`` in its own venv (newton 1.8.0):

    python newton_sphere.py N SELF OUT.npz [SECONDS]

A 1 m cloth of N x N particles 0.32 m above a static sphere (r = 0.3 m) at the origin, Z up,
SECONDS (default 1) at 60 frames per second, 10 substeps of 10 VBD iterations (Newton's cloth examples),
areal density 0.23 kg/m^2. The first frame (kernel compilation) is timed apart. Writes the
final positions [m], the triangles, start-up and wall seconds to OUT.npz.
"""
import sys
import time

import numpy as np

t0 = time.perf_counter()
import newton  # noqa: E402
import warp as wp  # noqa: E402

wp.config.quiet = True
n, self_contact, out = int(sys.argv[1]), sys.argv[2] == "1", sys.argv[3]
seconds = float(sys.argv[4]) if len(sys.argv) > 4 else 1.0
fps, substeps, iterations = 60, 10, 10
builder = newton.ModelBuilder(up_axis=newton.Axis.Z)
cell = 1.0 / (n - 1)
builder.add_cloth_grid(pos=wp.vec3(-0.5, -0.5, 0.62), rot=wp.quat_identity(), vel=wp.vec3(0.0), dim_x=n - 1,
                       dim_y=n - 1, cell_x=cell, cell_y=cell, mass=0.23 * cell * cell, tri_ke=1.0e4, tri_ka=1.0e4,
                       tri_kd=1.0e-1, edge_ke=1.0e-3, edge_kd=0.0, particle_radius=0.004)
builder.add_shape_sphere(body=-1, xform=wp.transform(wp.vec3(0.0, 0.0, 0.0), wp.quat_identity()), radius=0.3)
builder.color(include_bending=True)
model = builder.finalize(device="cpu")
model.soft_contact_ke, model.soft_contact_kd, model.soft_contact_mu = 1.0e3, 1.0e-2, 0.6
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
for _ in range(frames - 1):
    frame()
wp.synchronize()
wall = (time.perf_counter() - t) * frames / (frames - 1)
np.savez(out, points=states[0].particle_q.numpy(), triangles=model.tri_indices.numpy(), setup_seconds=setup,
         wall_seconds=wall,
         simulated_seconds=frames / fps)
