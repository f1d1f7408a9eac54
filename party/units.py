"""Unit conversions, all in one place.

Inside party everything is SI: metres, kilograms, seconds, newtons. Values printed in other
units (the paper's Table 1 in gram-force and centimetres, Kawabata's KES units, patterns in
centimetres) are converted here and nowhere else.
"""

GRAVITY = 9.80665
"""Standard gravity [m/s^2]; also the gram-force to newton factor times 1e3."""

GRAM_FORCE = 9.80665e-3
"""One gram-force in newtons [N]."""

CM = 1.0e-2
"""One centimetre in metres [m]."""

MM = 1.0e-3
"""One millimetre in metres [m]."""

INCH = 2.54e-2
"""One inch in metres [m]."""

LENGTH_UNITS = {"m": 1.0, "cm": CM, "mm": MM, "in": INCH}
"""Length units accepted in pattern and body files, in metres."""


def length_unit(name: str) -> float:
    """Metres per unit of ``name`` (m, cm, mm, in)."""
    from .errors import InvalidInput

    if name not in LENGTH_UNITS:
        raise InvalidInput(f"unknown length unit {name!r} (expected one of {', '.join(LENGTH_UNITS)})")
    return LENGTH_UNITS[name]


def areal_density_from_g_per_cm2(rho: float) -> float:
    """Mass per unit area: g/cm^2 -> kg/m^2 (x 10). Table 1's 0.023 g/cm^2 is 0.23 kg/m^2."""
    return rho * 1.0e-3 / (CM * CM)


def tensile_stiffness_from_table1(e: float) -> float:
    """The paper's stretch "restoring force" (Table 1, printed g/cm^2) -> tensile stiffness [N/m].

    Our reading: the printed figure is a gram-force per centimetre of fabric width per unit
    strain, i.e. gf/cm per (cm/cm), which the paper prints as g/cm^2. A strip of width w and
    length l then has spring constant e * w / l; a square element of the net (w = l) has
    spring constant e itself, so e_ik in f_spring = sum_k e_ik l_ik d_ik (section 5) is
    e [gf/cm] = e * 9.80665e-3 N / 1e-2 m. Table 1's warp value 1000 becomes 980.665 N/m.

    Why this reading: (1) it makes the net mesh-independent (a continuum membrane of tensile
    stiffness K has element constants K * w / l on a grid, independent of spacing); (2) at the
    paper's dt = 1e-4 s it puts a 1 cm net just inside explicit stability
    (dt_crit = 2 / (2 sqrt(k/m)) = 1.5e-4 s), matching the paper's choice of dt; (3) the
    fabric it describes is plausible for wool flannel: a 1 m strip hanging under its own
    weight (0.23 kg/m^2) carries 2.26 N/m at the top and stretches by 0.23 % there
    (0.115 % on average), and 500 gf/cm (the KES-FB1 test load) would stretch it 50 %,
    i.e. it is stopped by the plastic limit L_sh = 9.95 % long before; measured woven wools
    (KES EMT 3-10 %) stretch that far only under the full test load, so the net is a little
    soft at large load, as the paper itself says of its linear springs.
    """
    return e * GRAM_FORCE / CM


def damping_from_table1(rho_visco: float) -> float:
    """The paper's damping coefficient rho_visco (Table 1: 4.0) -> kg/(m^2 s).

    Eq. (3) divides the net force by rho (mass per unit area), so the paper's forces are per
    unit area and rho_visco is read in g/(cm^2 s): the viscous force on a node is
    rho_visco * A * sum_k (v_k - v_i) with A the node's area. 4.0 g/(cm^2 s) = 40 kg/(m^2 s),
    a relative-velocity damping rate rho_visco / rho = 174 1/s per neighbour for wool flannel
    (well inside explicit stability: 8 * 174 * 1e-4 = 0.14 < 2).
    """
    return rho_visco * 1.0e-3 / (CM * CM)


def bending_rigidity_from_kes(b: float) -> float:
    """Kawabata (KES-FB2) bending rigidity B: gf*cm^2/cm -> N*m (x 9.80665e-5)."""
    return b * GRAM_FORCE * CM


def bending_hysteresis_from_kes(two_hb: float) -> float:
    """Kawabata bending hysteresis 2HB: gf*cm/cm -> N*m/m (x 9.80665e-3)."""
    return two_hb * GRAM_FORCE


def shear_stiffness_from_kes(g: float) -> float:
    """Kawabata (KES-FB1) shear stiffness G: gf/cm per degree -> N/m per radian (x 56.19)."""
    import math

    return g * GRAM_FORCE / CM * 180.0 / math.pi


def areal_density_from_mg_per_cm2(w: float) -> float:
    """Kawabata weight W: mg/cm^2 -> kg/m^2 (x 1e-2)."""
    return w * 1.0e-2


def tensile_stiffness_from_kes(emt_percent: float) -> float:
    """Secant tensile stiffness [N/m] from Kawabata's extensibility EMT [%], the strain at the
    KES-FB1 load of 500 gf/cm: 500 gf/cm / (EMT / 100)."""
    return 500.0 * GRAM_FORCE / CM / (emt_percent / 100.0)
