"""Garments: a pattern meshed into panels side by side (``assemble``), placed around a body
(``dressing``), checked against it (``checks``), sewn onto it (``sewing``) and made the model of
a worn garment (``worn``)."""
