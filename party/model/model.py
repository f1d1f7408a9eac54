"""The finalized, read-only description of a simulation."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp

from .state import Control, State


@dataclass(frozen=True)
class HostArrays:
    """The model's set-up data on the host (NumPy), for set-up work, checks and output.

    Attributes:
        points: Node positions at set-up [m], shape (n, 3).
        mass: Lumped node masses [kg], shape (n,).
        kinematic: Whether each node is kinematic (pinned or driven), bool shape (n,).
        elements: The nodes (i, k) of each element, shape (e, 2).
        element_rest_length: l0 [m] per element.
        element_stiffness: Spring constant [N/m] per element.
        element_damping: Damper coefficient [kg/s] per element.
        element_max_length: (1 + L_sh) l0 [m] per element; infinite where it has no plastic
            limit.
        triangles: Cloth triangles' nodes, shape (t, 3).
        hinge_nodes, hinge_weights: Each bending stencil's nodes and curvature weights.
        hinge_stiffness, hinge_friction: Each stencil's bending and hysteresis stiffness [N*m^3].
        membrane_area: Rest area [m^2] of each membrane triangle (0 for the others).
        ignored_parts: See ``node_ignored_parts`` of :class:`Model`.
        cloths: The cloths added, in order.
        colliders: The colliders added, in order.
    """

    points: np.ndarray
    mass: np.ndarray
    kinematic: np.ndarray
    elements: np.ndarray
    element_rest_length: np.ndarray
    element_stiffness: np.ndarray
    element_damping: np.ndarray
    element_max_length: np.ndarray
    triangles: np.ndarray
    hinge_nodes: np.ndarray
    hinge_weights: np.ndarray
    hinge_stiffness: np.ndarray
    hinge_friction: np.ndarray
    membrane_area: np.ndarray
    ignored_parts: np.ndarray
    cloths: tuple
    colliders: tuple


@dataclass(frozen=True, eq=False)
class Model:
    """Everything that does not change during a run, on one Warp device.

    Node arrays have shape [node_count]; element arrays [element_count]; triangle arrays
    [triangle_count]. Units: m, kg, s, N.

    Attributes:
        node_mass: Lumped node mass [kg], float.
        node_inv_mass: 1/mass [1/kg], 0 for kinematic nodes (pinned or driven by a handle).
        node_friction, node_restitution: mu and sigma of the node's fabric (eqs. 10-11).
        node_gamma, node_kappa: gamma and kappa of the node's fabric (eqs. 13-14).
        node_thickness: eps of the node's fabric [m] (section 6.1).
        node_element_offsets, node_element_ids: CSR list of the elements at each node.
        node_neighbor_offsets, node_neighbors: CSR list of each node's mesh neighbours (nodes
            sharing a triangle), excluded from cloth-cloth response (section 6.3).
        node_near_offsets, node_near: CSR list of the nodes less than
            :data:`~party.model.builder.FOLD_REACH` times the node's thickness from it along
            the net at rest: cloth that close cannot fold back onto the node, so their
            triangles are no collision partners of it.
        element_nodes: (i, k) per element, vec2i.
        element_rest_length: l0_ik [m].
        element_stiffness: e_ik as a spring constant [N/m].
        element_damping: Viscous coefficient [kg/s] of the element's damper.
        element_max_length: (1 + L_sh) * l0 [m]; 1e30 when the element has no plastic limit
            (:attr:`limited_elements`).
        element_color_offsets, element_colored: the elements with a plastic limit, grouped so
            that no two in a group share a node (host offsets, device ids), for the
            plastic-limit passes.
        triangle_nodes: (a, b, c) per cloth triangle, int32 shape [t, 3].
        membrane_count: Triangles that carry a continuum membrane (``Fabric.membrane``).
        triangle_inv_rest: Inverse of each triangle's rest edge matrix [e1 e2] in the
            warp-aligned pattern plane [1/m], mat22.
        triangle_membrane_area: Rest area [m^2] of each membrane triangle, 0 for the others.
        triangle_membrane_c: Plane-stress stiffness [N/m] of each triangle, (E11, E22, 2 E12)
            to stress resultants, mat33.
        hinge_nodes: The nodes of each bending stencil (:mod:`party.meshing.hinges`), vec4i.
        hinge_weights: Weights K of each stencil's curvature vector k = sum_i K_i x_i
            [1/m^2], vec4.
        hinge_stiffness: B * scale [N*m^3] of each stencil: its energy is
            stiffness * |k|^2 / 2.
        hinge_friction: Stiffness of each stencil's bending-hysteresis (Jenkins) element while
            it sticks [N*m^3]: energy friction * |k - k_slip|^2 / 2, with k_slip the
            State's ``hinge_slip``; 0 without hysteresis.
        hinge_slip_limit: The largest |friction * (k - k_slip)| before the element slips
            [N*m]: HB * scale.
        collider_faces: Triangles of all colliders together, int32 shape [c, 3].
        node_ignored_parts: The body parts (bits of :mod:`party.body.segmentation`) each node
            passes through, int32; 0 for a node that collides with all of the body.
        collider_face_parts, collider_vertex_parts: The body parts of each collider face (all
            three corners in the part) and of each collider vertex, int32; 0 in none.
        collider_rest_points: Collider vertex positions at set-up [m].
        collider_normals: Collider normals at each face corner at set-up, unit, vec3 shape
            [c, 3] (smooth across soft edges, the face normal across creases).
        gravity: G [m/s^2], vec3.
    """

    device: str
    node_count: int
    element_count: int
    triangle_count: int
    node_rest_points: wp.array
    node_uv: np.ndarray
    node_mass: wp.array
    node_inv_mass: wp.array
    node_friction: wp.array
    node_restitution: wp.array
    node_gamma: wp.array
    node_kappa: wp.array
    node_thickness: wp.array
    node_element_offsets: wp.array
    node_element_ids: wp.array
    node_neighbor_offsets: wp.array
    node_neighbors: wp.array
    node_near_offsets: wp.array
    node_near: wp.array
    element_nodes: wp.array
    element_rest_length: wp.array
    element_stiffness: wp.array
    element_damping: wp.array
    element_max_length: wp.array
    element_color_offsets: tuple[int, ...]
    element_colored: wp.array
    triangle_nodes: wp.array
    membrane_count: int
    triangle_inv_rest: wp.array
    triangle_membrane_area: wp.array
    triangle_membrane_c: wp.array
    hinge_count: int
    hinge_nodes: wp.array
    hinge_weights: wp.array
    hinge_stiffness: wp.array
    hinge_friction: wp.array
    hinge_slip_limit: wp.array
    collider_names: tuple[str, ...]
    collider_face_ranges: tuple[tuple[int, int], ...]
    node_ignored_parts: wp.array
    collider_face_parts: wp.array
    collider_vertex_parts: wp.array
    collider_faces: wp.array
    collider_rest_points: wp.array
    collider_normals: wp.array
    collider_velocity: np.ndarray
    gravity: wp.vec3
    host: HostArrays

    def state(self, *, velocity=None) -> State:
        """A new State at the set-up positions, at rest unless ``velocity`` [m/s] is given."""
        q = wp.clone(self.node_rest_points)
        v = wp.zeros(self.node_count, dtype=wp.vec3, device=self.device)
        if velocity is not None:
            v.assign(np.broadcast_to(np.asarray(velocity, np.float32), (self.node_count, 3)).copy())
        cq = wp.clone(self.collider_rest_points)
        cv = wp.array(self.collider_velocity.astype(np.float32), dtype=wp.vec3, device=self.device)
        slip = wp.zeros(self.hinge_count, dtype=wp.vec3, device=self.device)
        return State(node_q=q, node_qd=v, collider_q=cq, collider_qd=cv, hinge_slip=slip, time=0.0)

    def control(self) -> Control:
        """Default control: no wind, kinematic nodes held still."""
        return Control(
            wind=(0.0, 0.0, 0.0),
            kinematic_velocity=wp.zeros(self.node_count, dtype=wp.vec3, device=self.device),
        )

    def bending_matrix(self, *, friction: bool = True):
        """L = sum_h stiffness_h K_h K_h^T [N/m], the constant matrix of the bending stencils'
        quadratic energy x^T L x / 2 (per coordinate; :mod:`party.meshing.hinges`), with the
        bending hysteresis's sticking stiffness unless ``friction`` is False, as a scipy CSR
        matrix with sorted rows."""
        import scipy.sparse as sp

        h = self.host
        nodes, weights = h.hinge_nodes, h.hinge_weights
        stiffness = h.hinge_stiffness + (h.hinge_friction if friction else 0.0)
        rows = np.repeat(nodes, 4, axis=1).ravel()
        cols = np.tile(nodes, (1, 4)).ravel()
        values = (stiffness[:, None, None] * weights[:, :, None] * weights[:, None, :]).ravel()
        matrix = sp.coo_matrix((values, (rows, cols)), shape=(self.node_count, self.node_count)).tocsr()
        matrix.sum_duplicates()
        matrix.sort_indices()
        return matrix

    @property
    def triangles(self) -> np.ndarray:
        """Cloth triangles on the host, shape (t, 3)."""
        return self.host.triangles

    @property
    def elements(self) -> np.ndarray:
        return self.host.elements

    @property
    def limited_elements(self) -> np.ndarray:
        """Which elements have a plastic limit (bool per element, on the host)."""
        return np.isfinite(self.host.element_max_length)

    @property
    def kinematic(self) -> np.ndarray:
        return self.host.kinematic

    @property
    def collider_count(self) -> int:
        return len(self.collider_names)
