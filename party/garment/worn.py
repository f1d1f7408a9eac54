"""The model of a garment worn on a body."""

from __future__ import annotations

import numpy as np

from ..body.body import Body
from ..fabric import Fabric
from ..meshing.net import ClothNet
from ..model import Model, ModelBuilder


def garment_model(net: ClothNet, fabric: Fabric, points: np.ndarray, body: Body, *, gravity: bool = True,
                  device: str | None = None, name: str = "garment", sewn: bool = True,
                  ignored_parts: np.ndarray | None = None) -> Model:
    """The model of a garment ``net`` at ``points`` [m] on ``body``. Once ``sewn``, elements
    that ``points`` stretch beyond the fabric's strain limit keep that length as their limit
    (:meth:`~party.model.ModelBuilder.yield_to_placement`): a pattern smaller than its wearer
    can only be worn stretched, and a plastic limit fighting the body's collision response for
    a length it cannot reach would let the stretch grow every step instead. ``ignored_parts`` (n,)
    are the body parts each node passes through (:mod:`party.garment.body_parts`)."""
    builder = ModelBuilder() if gravity else ModelBuilder(gravity=(0.0, 0.0, 0.0))
    builder.add_cloth(net, fabric, points, name=name)
    if sewn:
        builder.yield_to_placement()
    if ignored_parts is not None:
        builder.ignore_body_parts(np.arange(len(ignored_parts)), ignored_parts)
    for collider in body.colliders:
        builder.add_collider(collider)
    return builder.finalize(device)
