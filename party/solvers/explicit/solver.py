"""The paper's explicit integrator (eqs. 3-5)."""

from __future__ import annotations

import numpy as np
import warp as wp

from ...collision import CollisionSettings
from ...errors import InvalidInput
from ...launch import launch
from ...model import Control, Model, State
from ..aero import Air, AirForces
from ..filters import StepFilters
from ..plastic_limit import OVER_RELAXATION
from .kernels import hinge_forces, kinetic_damping, net_forces_and_velocity


PAPER_DT = 1.0e-4
"""The paper's time step [s] (section 7), on a net of about 1 cm."""

STABLE_SHARE = 0.9
"""Share of :func:`critical_time_step` that relaxations and dynamics step at: the limit is
computed for the net at rest, and stretched or compressed cloth is a little stiffer."""


class SolverExplicit:
    """Symplectic Euler on the elastic net with collision as a velocity filter:

        v* = v(t) + (df / rho + G) dt                     (3)
        v(t + dt) = Collision(v*)                          (5)
        r(t + dt) = r(t) + v(t + dt) dt                    (4)

    with df = f_spring + f_visco + f_ext (f_ext: wind and, beyond the paper, bending) and the plastic limit f_plas applied to v* before
    Collision (section 5). Stable while dt is below :meth:`critical_time_step`; the paper uses
    dt = 1e-4 s on a net of about 1 cm.

    Args:
        model: The model to advance.
        collision: Collision settings (section 6); ``None`` switches collision off.
        air: Wind and air drag (see :mod:`party.solvers.aero`); ``None`` for none.
        plastic_passes: Most sweeps over the element colours per step enforcing the plastic
            limit (sweeps stop as soon as no element is beyond it).
        kinetic_damping: ``(max_speed [m/s], keep [-])`` to filter v* for static relaxation
            (:mod:`party.solvers.relax`); None for dynamics. Dynamics applies the paper's f_plas
            as it is; relaxation, which seeks only the rest shape, over-relaxes its sweeps
            (:class:`~party.solvers.filters.StepFilters`), and where it holds the body's vertices
            off the cloth (``collision.body_vertices``) enforces the limit again after contact,
            as the implicit solver does: their push on a tight hem otherwise outran the limit.
    """

    name = "explicit"
    default_dt = PAPER_DT
    settle_seconds = 30.0
    creep = 1.0

    def __init__(self, model: Model, *, collision: CollisionSettings | None = CollisionSettings(),
                 air: Air | None = None, plastic_passes: int = 32,
                 kinetic_damping: tuple[float, float] | None = None) -> None:
        if model.membrane_count:
            raise InvalidInput("the continuum membrane (a fabric with membrane = true) is integrated by the implicit "
                               "solver only; use --solver implicit")
        self.model = model
        self.kinetic_damping = kinetic_damping
        relaxing = kinetic_damping is not None
        self.filters = StepFilters(model, collision, plastic_passes, max_speed=kinetic_damping[0] if relaxing else None,
                           plastic_over_relaxation=OVER_RELAXATION if relaxing else 1.0,
                           limit_after_contact=relaxing and collision is not None and collision.body_vertices)
        self.collision = self.filters.collision
        self.air = AirForces(model, air) if air is not None else None
        self._f_ext = wp.zeros(model.node_count, dtype=wp.vec3, device=model.device)
        self._bending_stiffness = wp.array((model.host.hinge_stiffness + model.host.hinge_friction).astype(np.float32),
                                           dtype=float, device=model.device)

    @classmethod
    def configured(cls, model: Model, *, collision: CollisionSettings | None = CollisionSettings(),
                   air: Air | None = None, static: bool = False, kinetic_damping: tuple[float, float] | None = None,
                   **implicit_only) -> "SolverExplicit":
        """The paper's integrator with its Collision() as printed (``static`` changes nothing:
        the explicit step is the same whatever the run seeks)."""
        given = [name for name, value in implicit_only.items() if value is not None]
        if given:
            raise InvalidInput(f"{', '.join(given)} apply to the implicit solver only")
        return cls(model, collision=collision, air=air, kinetic_damping=kinetic_damping)

    @classmethod
    def relaxation_step(cls, model: Model) -> float:
        """:data:`STABLE_SHARE` of the stability limit (which allows for the dampers)."""
        return STABLE_SHARE * critical_time_step(model)

    @classmethod
    def dynamics_step(cls, model: Model, resolve_period: float | None = None) -> float:
        """The paper's step, or :data:`STABLE_SHARE` of the stability limit where that is
        shorter; any motion is resolved at steps that small."""
        return min(cls.default_dt, STABLE_SHARE * critical_time_step(model))

    def stable_time_step(self) -> float:
        """See :meth:`critical_time_step`."""
        return self.critical_time_step()

    def flush(self, state: State) -> None:
        """Run a crossing check that the guard's interval has left pending."""
        self.filters.flush(state)

    def critical_time_step(self) -> float:
        """Largest stable dt [s] of the net at rest with its dampers. For one mode
        x'' = -w^2 x - c x', symplectic Euler is stable while w^2 dt^2 + 2 c dt < 4, so

            dt_crit = (sqrt(c^2 + 4 w^2) - c) / w^2   (2 / w without damping)

        with w^2 the largest eigenvalue of M^-1/2 K M^-1/2 (K the springs' and the bending
        stencils' stiffness, M the
        lumped masses) and c that of M^-1/2 C M^-1/2 (C the dampers' Laplacian), taken
        together as if they were one mode (conservative)."""
        return critical_time_step(self.model)

    def step(self, state_in: State, state_out: State, control: Control, dt: float) -> None:
        """Advance ``state_in`` by ``dt`` [s] into ``state_out`` (distinct objects; swap after)."""
        if not dt > 0.0:
            raise InvalidInput(f"time step must be positive, got {dt}")
        m = self.model
        dev = m.device
        self._f_ext.zero_()
        if self.air is not None:
            self.air.accumulate(state_in.node_q, state_in.node_qd, control.wind, self._f_ext)
        if m.hinge_count:
            launch(hinge_forces, dim=m.hinge_count,
                   inputs=[state_in.node_q, m.hinge_nodes, m.hinge_weights, self._bending_stiffness, self._f_ext],
                   device=dev)
            self.filters.hysteresis.add_forces(state_in, self._f_ext)
        launch(net_forces_and_velocity, dim=m.node_count,
               inputs=[state_in.node_q, state_in.node_qd, m.node_inv_mass, m.node_element_offsets,
                       m.node_element_ids, m.element_nodes, m.element_rest_length, m.element_stiffness,
                       m.element_damping, self._f_ext, m.gravity, control.kinematic_velocity, dt],
               outputs=[state_out.node_q, state_out.node_qd], device=dev)
        if self.kinetic_damping is not None:
            launch(kinetic_damping, dim=m.node_count,
                   inputs=[state_in.node_qd, state_out.node_qd, *map(float, self.kinetic_damping)], device=dev)
        self.filters.finish(state_in, state_out, dt)


def critical_time_step(model: Model) -> float:
    """See :meth:`SolverExplicit.critical_time_step`."""
    import scipy.sparse as sp

    h = model.host
    free = ~h.kinematic
    if model.element_count == 0 or not free.any():
        return float("inf")
    e, k = h.elements, h.element_stiffness
    p = h.points
    d = p[e[:, 1]] - p[e[:, 0]]
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-30)
    blocks = k[:, None, None] * d[:, :, None] * d[:, None, :]
    rows, cols, vals = [], [], []
    for a, b, sign in ((0, 0, 1.0), (1, 1, 1.0), (0, 1, -1.0), (1, 0, -1.0)):
        for r in range(3):
            for c in range(3):
                rows.append(3 * e[:, a] + r)
                cols.append(3 * e[:, b] + c)
                vals.append(sign * blocks[:, r, c])
    n = 3 * model.node_count
    K = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    if model.hinge_count:
        K = K + sp.kron(model.bending_matrix(), sp.identity(3), format="csr")
    scale = np.repeat(np.where(free, 1.0 / np.sqrt(h.mass), 0.0), 3)
    lam = _largest_eigenvalue(sp.diags(scale) @ K @ sp.diags(scale))
    c = h.element_damping
    nodes = model.node_count
    C = sp.csr_matrix((np.concatenate([c, c, -c, -c]), (np.concatenate([e[:, 0], e[:, 1], e[:, 0], e[:, 1]]),
                                                        np.concatenate([e[:, 0], e[:, 1], e[:, 1], e[:, 0]]))),
                      shape=(nodes, nodes))
    damping = _largest_eigenvalue(sp.diags(scale[::3]) @ C @ sp.diags(scale[::3])) if c.any() else 0.0
    if lam <= 0:
        return float("inf")
    return float((np.sqrt(damping**2 + 4.0 * lam) - damping) / lam)


def _largest_eigenvalue(A) -> float:
    if A.shape[0] <= 600:
        return float(np.linalg.eigvalsh(A.toarray()).max())
    from scipy.sparse.linalg import eigsh

    # a fixed start vector: ARPACK's random one made dt, and so every run, differ in the last digits
    start = np.random.default_rng(0).standard_normal(A.shape[0])
    return float(eigsh(A, k=1, which="LA", return_eigenvectors=False, tol=1e-3, v0=start)[0])
