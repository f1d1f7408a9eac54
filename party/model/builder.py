"""Assembling a :class:`Model` from cloth nets, fabrics, pins and colliders."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp

from .. import device as devices
from ..body.collider import ColliderMesh
from ..errors import InvalidInput
from ..fabric import Fabric
from ..meshing.hinges import hinges
from ..meshing.net import ClothNet, ElementKind
from ..units import GRAVITY
from .csr import csr_order
from .model import HostArrays, Model
from .nearby import nodes_within

FOLD_REACH = 0.5 * np.pi
"""Cloth of thickness eps folded back onto itself turns through a half circle of diameter eps,
a length of pi eps / 2: points nearer than this along the net at rest cannot touch. Their
triangles are left out of each other's cloth-cloth collision (``Model.node_near``); where
the net is finer than the thickness, neighbouring triangles of one flat layer would lie within
eps of each node and push a flat sheet at rest apart."""

HYSTERESIS_STIFFNESS = 20.0
"""Stiffness of a bending stencil's hysteresis element while it sticks, in units of the
stencil's bending stiffness. KES gives none: Kawabata's and Grosberg's bilinear loop turns
rigidly at a curvature reversal (the frictional couple must be overcome before any bending),
and a yarn whose fibres do not slip bends as a solid bundle, stiffer than free fibres by up to
their number. Here the loop turns over 2HB / ((1 + 20) B), about 1 % of the KES-FB2 test's
range. The measured fabrics' Cusick drapes (``party validate --case cusick-measured``) match
their measured folds from this stiffness on and no longer change with it; at a quarter of it
they fold once too often."""


@dataclass(frozen=True)
class ClothRange:
    """Where one cloth's nodes and triangles sit in the model's arrays."""

    name: str
    node_start: int
    node_end: int
    triangle_start: int
    triangle_end: int
    net: ClothNet

    def nodes(self, local) -> np.ndarray:
        """Model node indices of this cloth's local node indices."""
        local = np.asarray(local, dtype=int)
        if np.any(local < 0) or np.any(local >= self.node_end - self.node_start):
            raise InvalidInput(f"cloth {self.name!r}: node index out of range [0, {self.node_end - self.node_start})")
        return local + self.node_start


class ModelBuilder:
    """Collects nodes, elements, triangles and colliders, then :meth:`finalize` checks them and
    puts them on a device. Z is up; ``gravity`` is G of eq. (3) [m/s^2]."""

    def __init__(self, gravity=(0.0, 0.0, -GRAVITY)) -> None:
        self.gravity = tuple(float(g) for g in gravity)
        self._points: list[np.ndarray] = []
        self._uv: list[np.ndarray] = []
        self._mass: list[np.ndarray] = []
        self._material: list[np.ndarray] = []  # per node: mu, sigma, gamma, kappa, eps
        self._elements: list[np.ndarray] = []
        self._element_params: list[np.ndarray] = []  # rest, stiffness, damping, max length
        self._triangles: list[np.ndarray] = []
        self._hinges: list[tuple] = []  # nodes, weights, stiffness, friction stiffness, slip limit
        self._membranes: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # inverse rest, area, C
        self._kinematic: set[int] = set()
        self._ignored_parts: list[tuple[np.ndarray, np.ndarray]] = []  # nodes, body-part bits they pass through
        self._colliders: list[ColliderMesh] = []
        self.cloths: list[ClothRange] = []
        self._node_count = 0
        self._triangle_count = 0

    @property
    def node_count(self) -> int:
        return self._node_count

    @property
    def element_stiffness(self) -> np.ndarray:
        """Spring constants [N/m] of the elements added so far."""
        return np.concatenate([p[:, 1] for p in self._element_params]) if self._element_params else np.zeros(0)

    def add_node(self, point, mass: float, *, fabric: Fabric | None = None) -> int:
        """Add a lone node [m, kg]; ``fabric`` gives its collision parameters."""
        return int(self._add_nodes(np.asarray(point, float).reshape(1, 3), np.array([mass]), fabric)[0])

    def add_element(self, i: int, k: int, *, stiffness: float, damping: float = 0.0,
                    rest_length: float | None = None, strain_limit: float = np.inf) -> None:
        """Add one spring-damper-plastic element (figure 4) between nodes i and k.

        ``stiffness`` is the spring constant e_ik [N/m], ``damping`` the damper [kg/s],
        ``rest_length`` l0 [m] (default: the current distance), ``strain_limit`` L_sh [-].
        """
        self.add_springs(np.array([[i, k]]), stiffness=stiffness, damping=damping,
                         rest_length=rest_length, strain_limit=strain_limit)

    def add_springs(self, pairs, *, stiffness, damping=0.0, rest_length=None, strain_limit=np.inf) -> None:
        """Add elements between node ``pairs`` (m, 2) at once; the other arguments are scalars or
        arrays of length m, as in :meth:`add_element` (sewing springs are added this way)."""
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        if pairs.size and (pairs.min() < 0 or pairs.max() >= self._node_count):
            raise InvalidInput(f"element node index out of range [0, {self._node_count})")
        m = len(pairs)
        if rest_length is None:
            pts = np.concatenate(self._points)
            rest_length = np.linalg.norm(pts[pairs[:, 1]] - pts[pairs[:, 0]], axis=1)
        self._push_elements(pairs, *(np.broadcast_to(np.asarray(x, float), (m,)).copy()
                                     for x in (rest_length, stiffness, damping, strain_limit)))

    def add_cloth(self, net: ClothNet, fabric: Fabric, points, *, name: str = "cloth") -> ClothRange:
        """Add a cloth cut from ``net`` in ``fabric``, its nodes placed at ``points`` [m].

        Rest lengths come from the flat net (the pattern), not from the placement, so a cloth
        placed curved starts unstretched only if the placement preserves lengths.
        """
        points = np.asarray(points, float)
        if points.shape != (net.node_count, 3):
            raise InvalidInput(f"cloth {name!r}: expected {net.node_count} points of 3 coordinates, got shape {points.shape}")
        masses = fabric.areal_density * net.node_areas()
        node_start, tri_start = self._node_count, self._triangle_count
        self._add_nodes(points, masses, fabric, uv=net.uv)

        rest = net.element_rest_lengths()
        # A quad's two diagonals of constant k give it shear stiffness k per unit width; a
        # diagonal standing for half the quad's diagonal (width d / 2) needs 2 G w / l = G.
        tensile = {ElementKind.WARP: fabric.tensile_warp, ElementKind.WEFT: fabric.tensile_weft,
                   ElementKind.SHEAR: 2.0 * fabric.shear}
        modulus = np.array([tensile[ElementKind(k)] for k in range(len(ElementKind))])[net.kinds]
        share = net.element_warp_share()
        in_plane = np.isin(net.kinds, [ElementKind.WARP, ElementKind.WEFT])
        warp, weft = net_tensile_moduli(fabric, diagonals=bool(np.any(net.kinds == ElementKind.SHEAR)))
        modulus = np.where(in_plane, share * warp + (1.0 - share) * weft, modulus)
        keep = modulus > 0.0
        if fabric.membrane:  # the triangles carry the elasticity; warp and weft keep damper and limit
            modulus = np.zeros_like(modulus)
            keep = in_plane
        limited = np.isin(net.kinds, [ElementKind.WARP, ElementKind.WEFT])
        self._push_elements(
            net.elements[keep] + node_start,
            rest[keep],
            (modulus * net.widths / np.maximum(rest, 1e-12))[keep],
            (fabric.damping * net.widths * rest)[keep],
            np.where(limited, fabric.strain_limit, np.inf)[keep],
        )
        self._triangles.append(net.triangles + node_start)
        self._triangle_count += len(net.triangles)
        self._membranes.append(_membrane(net, fabric))
        if fabric.bending_rigidity > 0.0:
            nodes, weights, scale = hinges(net)
            # Thread stencils only (a twist stencil's fourth weight is not 0): summed over the
            # two threads, the frictional moment on a cylinder of any direction is then HB, as
            # |cos^2| + |sin^2| = 1; twist stencils with it too would double it on the bias.
            thread = weights[:, 3] == 0.0
            friction = np.where(thread & (fabric.bending_hysteresis > 0),
                                HYSTERESIS_STIFFNESS * fabric.bending_rigidity * scale, 0.0)
            self._hinges.append((nodes + node_start, weights, fabric.bending_rigidity * scale, friction,
                                 0.5 * fabric.bending_hysteresis * scale))
        cloth = ClothRange(name, node_start, self._node_count, tri_start, self._triangle_count, net)
        self.cloths.append(cloth)
        return cloth

    def pin(self, nodes) -> None:
        """Make nodes kinematic: held still, or moved by a handle through ``Control``."""
        nodes = np.atleast_1d(np.asarray(nodes))
        if nodes.size and (not np.issubdtype(nodes.dtype, np.integer) or nodes.min() < 0 or nodes.max() >= self._node_count):
            raise InvalidInput(f"pinned node index out of range [0, {self._node_count}): {nodes.tolist()[:5]}")
        self._kinematic.update(int(n) for n in nodes)

    def ignore_body_parts(self, nodes, parts) -> None:
        """Let each of ``nodes`` pass through the colliders' faces and vertices of the body parts
        ``parts`` (bits of :mod:`party.body.segmentation`, one for all or one per node):
        GarmentCode's collision filter, a skirt's cloth through the arms."""
        nodes = np.atleast_1d(np.asarray(nodes, np.int64))
        if nodes.size and (nodes.min() < 0 or nodes.max() >= self._node_count):
            raise InvalidInput(f"filtered node index out of range [0, {self._node_count})")
        self._ignored_parts.append((nodes, np.broadcast_to(np.asarray(parts, np.int32), nodes.shape)))

    def add_collider(self, collider: ColliderMesh) -> None:
        if not isinstance(collider, ColliderMesh):
            raise InvalidInput("colliders must be ColliderMesh objects (see party.body)")
        self._colliders.append(collider)

    def _add_nodes(self, points: np.ndarray, masses: np.ndarray, fabric: Fabric | None, uv=None) -> np.ndarray:
        if not np.all(np.isfinite(points)):
            bad = int(np.argwhere(~np.isfinite(points).all(axis=1))[0, 0]) + self._node_count
            raise InvalidInput(f"node {bad} has a non-finite position (NaN or inf)")
        if not np.all(np.isfinite(masses) & (masses > 0)):
            raise InvalidInput("node masses must be positive and finite (check the fabric's areal density)")
        fabric = fabric or Fabric("default", 0.1, 1.0, 1.0, 0.0)
        start = self._node_count
        self._points.append(points)
        self._uv.append(np.zeros((len(points), 2)) if uv is None else np.asarray(uv, float))
        self._mass.append(masses)
        material = [fabric.friction, fabric.restitution, fabric.momentum_propagation,
                    fabric.cloth_friction, fabric.thickness]
        self._material.append(np.tile(material, (len(points), 1)))
        self._node_count += len(points)
        return np.arange(start, self._node_count)

    def yield_to_placement(self) -> tuple[int, float]:
        """Raise the plastic limit of every element that its nodes' placement already stretches
        beyond it to that length, as if the cloth had yielded there (a garment sewn tighter than
        its wearer), so that the model starts within its limits; returns how many elements
        yielded and the largest length / rest length among them (1 when none did)."""
        points = np.concatenate(self._points)
        count, worst = 0, 1.0
        for pairs, params in zip(self._elements, self._element_params):
            length = np.linalg.norm(points[pairs[:, 1]] - points[pairs[:, 0]], axis=1)
            beyond = np.isfinite(params[:, 3]) & (length > params[:, 3])
            if beyond.any():
                params[beyond, 3] = length[beyond]
                count += int(beyond.sum())
                worst = max(worst, float((length[beyond] / params[beyond, 0]).max()))
        return count, worst

    def _push_elements(self, pairs, rest, stiffness, damping, strain_limit) -> None:
        if np.any(~np.isfinite(stiffness) | (stiffness < 0)):
            raise InvalidInput("element stiffness must be non-negative and finite")
        if np.any(~np.isfinite(damping) | (damping < 0)):
            raise InvalidInput("element damping must be non-negative and finite")
        if np.any(~np.isfinite(rest) | (rest <= 0)):
            raise InvalidInput("element rest length must be positive (two nodes of an element coincide)")
        if np.any(pairs[:, 0] == pairs[:, 1]):
            raise InvalidInput("an element joins a node to itself")
        max_length = np.where(np.isfinite(strain_limit), rest * (1.0 + strain_limit), np.inf)
        self._elements.append(np.asarray(pairs, np.int32))
        self._element_params.append(np.stack([rest, stiffness, damping, max_length], axis=1))

    def finalize(self, device: str | None = None) -> Model:
        """Check everything and build the immutable :class:`Model` on ``device``."""
        device = devices.resolve(device)
        if self._node_count == 0:
            raise InvalidInput("the model has no nodes")
        points = np.concatenate(self._points)
        mass = np.concatenate(self._mass)
        material = np.concatenate(self._material)
        elements = np.concatenate(self._elements) if self._elements else np.zeros((0, 2), np.int32)
        params = np.concatenate(self._element_params) if self._element_params else np.zeros((0, 4))
        triangles = np.concatenate(self._triangles) if self._triangles else np.zeros((0, 3), np.int32)
        hinge_nodes = np.concatenate([h[0] for h in self._hinges]) if self._hinges else np.zeros((0, 4), np.int32)
        hinge_weights = np.concatenate([h[1] for h in self._hinges]) if self._hinges else np.zeros((0, 4))
        hinge_stiffness = np.concatenate([h[2] for h in self._hinges]) if self._hinges else np.zeros(0)
        hinge_friction = np.concatenate([h[3] for h in self._hinges]) if self._hinges else np.zeros(0)
        hinge_slip_limit = np.concatenate([h[4] for h in self._hinges]) if self._hinges else np.zeros(0)
        inv_rest = np.concatenate([m[0] for m in self._membranes]) if self._membranes else np.zeros((0, 2, 2))
        membrane_area = np.concatenate([m[1] for m in self._membranes]) if self._membranes else np.zeros(0)
        membrane_c = np.concatenate([m[2] for m in self._membranes]) if self._membranes else np.zeros((0, 3, 3))
        kinematic = np.zeros(self._node_count, bool)
        kinematic[list(self._kinematic)] = True
        inv_mass = np.where(kinematic, 0.0, 1.0 / mass)
        ignored = np.zeros(self._node_count, np.int32)
        for nodes, parts in self._ignored_parts:
            np.bitwise_or.at(ignored, nodes, parts)
        face_parts = (np.concatenate([c.face_parts() for c in self._colliders]) if self._colliders
                      else np.zeros(0, np.int32))
        vertex_parts = (np.concatenate([c.vertex_part_bits() for c in self._colliders]) if self._colliders
                        else np.zeros(0, np.int32))

        n = self._node_count
        elem_offsets, elem_ids = _csr(np.concatenate([elements[:, 0], elements[:, 1]]),
                                      np.tile(np.arange(len(elements)), 2), n)
        edges = np.concatenate([elements, triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
        edges = np.unique(np.sort(edges, axis=1), axis=0) if len(edges) else edges
        nbr_offsets, nbr_ids = _csr(np.concatenate([edges[:, 0], edges[:, 1]]),
                                    np.concatenate([edges[:, 1], edges[:, 0]]), n)
        near_offsets, near_ids = nodes_within(elements, params[:, 0], FOLD_REACH * material[:, 4], n)
        limited_ids = np.flatnonzero(np.isfinite(params[:, 3])) if len(params) else np.zeros(0, np.int64)
        color_offsets, colored = _color_elements(elements[limited_ids], n)
        colored = limited_ids[colored].astype(np.int32)

        faces, rest_pts, normals, ranges, velocity, names = _merge_colliders(self._colliders)

        def arr(x, dtype):
            return wp.array(np.ascontiguousarray(x), dtype=dtype, device=device)

        max_len = params[:, 3].copy()
        max_len[~np.isfinite(max_len)] = 1e30
        return Model(
            device=device,
            node_count=n,
            element_count=len(elements),
            triangle_count=len(triangles),
            node_rest_points=arr(points.astype(np.float32), wp.vec3),
            node_uv=np.concatenate(self._uv),
            node_mass=arr(mass.astype(np.float32), wp.float32),
            node_inv_mass=arr(inv_mass.astype(np.float32), wp.float32),
            node_friction=arr(material[:, 0].astype(np.float32), wp.float32),
            node_restitution=arr(material[:, 1].astype(np.float32), wp.float32),
            node_gamma=arr(material[:, 2].astype(np.float32), wp.float32),
            node_kappa=arr(material[:, 3].astype(np.float32), wp.float32),
            node_thickness=arr(material[:, 4].astype(np.float32), wp.float32),
            node_element_offsets=arr(elem_offsets, wp.int32),
            node_element_ids=arr(elem_ids, wp.int32),
            node_neighbor_offsets=arr(nbr_offsets, wp.int32),
            node_neighbors=arr(nbr_ids, wp.int32),
            node_near_offsets=arr(near_offsets, wp.int32),
            node_near=arr(near_ids, wp.int32),
            element_nodes=arr(elements.astype(np.int32), wp.vec2i),
            element_rest_length=arr(params[:, 0].astype(np.float32), wp.float32),
            element_stiffness=arr(params[:, 1].astype(np.float32), wp.float32),
            element_damping=arr(params[:, 2].astype(np.float32), wp.float32),
            element_max_length=arr(max_len.astype(np.float32), wp.float32),
            element_color_offsets=tuple(int(c) for c in color_offsets),
            element_colored=arr(colored, wp.int32),
            triangle_nodes=arr(triangles.astype(np.int32), wp.int32),
            membrane_count=int((membrane_area > 0).sum()),
            triangle_inv_rest=arr(inv_rest.astype(np.float32), wp.mat22),
            triangle_membrane_area=arr(membrane_area.astype(np.float32), wp.float32),
            triangle_membrane_c=arr(membrane_c.astype(np.float32), wp.mat33),
            hinge_count=len(hinge_nodes),
            hinge_nodes=arr(hinge_nodes.astype(np.int32), wp.vec4i),
            hinge_weights=arr(hinge_weights.astype(np.float32), wp.vec4),
            hinge_stiffness=arr(hinge_stiffness.astype(np.float32), wp.float32),
            hinge_friction=arr(hinge_friction.astype(np.float32), wp.float32),
            hinge_slip_limit=arr(hinge_slip_limit.astype(np.float32), wp.float32),
            collider_names=names,
            collider_face_ranges=ranges,
            node_ignored_parts=arr(ignored, wp.int32),
            collider_face_parts=arr(face_parts.astype(np.int32), wp.int32),
            collider_vertex_parts=arr(vertex_parts.astype(np.int32), wp.int32),
            collider_faces=arr(faces, wp.int32),
            collider_rest_points=arr(rest_pts.astype(np.float32), wp.vec3),
            collider_normals=arr(normals.astype(np.float32), wp.vec3),
            collider_velocity=velocity,
            gravity=wp.vec3(*self.gravity),
            host=HostArrays(
                points=points, mass=mass, kinematic=kinematic, elements=elements,
                element_rest_length=params[:, 0], element_stiffness=params[:, 1], element_damping=params[:, 2],
                element_max_length=params[:, 3], triangles=triangles, hinge_nodes=hinge_nodes,
                hinge_weights=hinge_weights, hinge_stiffness=hinge_stiffness, hinge_friction=hinge_friction,
                membrane_area=membrane_area, ignored_parts=ignored, cloths=tuple(self.cloths),
                colliders=tuple(self._colliders),
            ),
        )


def net_tensile_moduli(fabric: Fabric, *, diagonals: bool) -> tuple[float, float]:
    """The tensile stiffness [N/m] the warp and weft elements carry, so that a strip of the net
    pulled along either grain line (free to narrow) has the fabric's tensile stiffness.

    The shear diagonals (2 G w / l each) stretch with the grid: a quad's pair adds G along the
    warp and along the weft and couples the two. With A = a + G and C = b + G for element
    moduli a (warp) and b (weft), a uniaxial pull along the warp stores
    (A - G^2 / C) eps^2 / 2 per unit area, and along the weft (C - G^2 / A) eps^2 / 2; setting
    these to the fabric's E_warp and E_weft gives

        A = E_warp / 2 + sqrt(E_warp^2 / 4 + E_warp G^2 / E_weft)   (C likewise, swapped)

    and the net's Poisson ratio G / C. Without diagonals (or with a membrane) a = E_warp and
    b = E_weft."""
    e1, e2, g = fabric.tensile_warp, fabric.tensile_weft, fabric.shear
    if not diagonals or fabric.membrane or g == 0.0:
        return e1, e2
    a = 0.5 * e1 + np.sqrt(0.25 * e1 * e1 + e1 * g * g / e2) - g
    b = 0.5 * e2 + np.sqrt(0.25 * e2 * e2 + e2 * g * g / e1) - g
    if min(a, b) <= 0.0:
        raise InvalidInput(f"fabric {fabric.name!r}: shear {g:.4g} N/m is too large for its tensile stiffnesses "
                           f"{e1:.4g}/{e2:.4g} N/m (the net's diagonals alone would be stiffer in stretch)")
    return float(a), float(b)


def _membrane(net: ClothNet, fabric: Fabric) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per triangle: the inverse of its rest edge matrix [e1 e2] in the warp-aligned pattern
    plane [1/m], its rest area [m^2] (0 when the fabric has no membrane) and the plane-stress
    stiffness C [N/m] taking the Green strain (E11, E22, 2 E12) to the stress resultants."""
    corners = net.rest_triangle_uv()
    edges = np.stack([corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]], axis=2)  # columns
    det = edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0]
    inverse = np.zeros_like(edges)
    ok = np.abs(det) > 1e-20
    inverse[ok] = np.linalg.inv(edges[ok])
    area = 0.5 * np.abs(det) if fabric.membrane else np.zeros(len(det))
    e1, e2, g, nu12 = fabric.tensile_warp, fabric.tensile_weft, fabric.shear, fabric.poisson
    nu21 = nu12 * e2 / e1
    scale = 1.0 / (1.0 - nu12 * nu21)
    c = np.array([[e1 * scale, nu21 * e1 * scale, 0.0], [nu12 * e2 * scale, e2 * scale, 0.0], [0.0, 0.0, g]])
    return inverse, area, np.broadcast_to(c, (len(det), 3, 3)).copy()


def _csr(rows: np.ndarray, values: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    offsets, order = csr_order(rows, n)
    return offsets.astype(np.int32), values[order].astype(np.int32)


def _color_elements(elements: np.ndarray, n: int) -> tuple[list[int], np.ndarray]:
    """Greedy edge colouring: no two elements of one colour share a node."""
    colors = np.full(len(elements), -1, np.int64)
    used: list[set[int]] = [set() for _ in range(n)]
    for e, (i, k) in enumerate(elements.tolist()):
        taken = used[i] | used[k]
        c = 0
        while c in taken:
            c += 1
        colors[e] = c
        used[i].add(c)
        used[k].add(c)
    order = np.argsort(colors, kind="stable")
    counts = np.bincount(colors, minlength=1) if len(colors) else np.zeros(0, int)
    offsets = [0] + np.cumsum(counts).tolist()
    return offsets, order.astype(np.int32)


def _merge_colliders(colliders: list[ColliderMesh]):
    faces, points, normals, ranges, velocities, names = [], [], [], [], [], []
    v0 = f0 = 0
    for c in colliders:
        faces.append(c.faces + v0)
        points.append(c.vertices)
        normals.append(c.corner_normals())
        velocities.append(np.tile(c.velocity, (len(c.vertices), 1)))
        ranges.append((f0, f0 + len(c.faces)))
        names.append(c.name)
        v0 += len(c.vertices)
        f0 += len(c.faces)
    if not colliders:
        return (np.zeros((0, 3), np.int32), np.zeros((0, 3)), np.zeros((0, 3, 3)), (), np.zeros((0, 3)), ())
    return (np.concatenate(faces).astype(np.int32), np.concatenate(points), np.concatenate(normals),
            tuple(ranges), np.concatenate(velocities), tuple(names))
