"""Goda's design wave pressure on a vertical breakwater (pure Python).

Goda (1974) "New wave pressure formulae for composite breakwaters", Proc. 14th ICCE;
Goda (2000) "Random Seas and Design of Maritime Structures", 2nd ed., chapter 4; the
Coastal Engineering Manual (USACE, EM 1110-2-1100) Part VI-5 (Goda's formula). The
quasi-static pressure of the highest wave H_max of the design sea state on the upright
section of a vertical (or composite) breakwater, per metre of breakwater (η*: the
elevation above the design water level, SWL, where the pressure vanishes; p₁, p₂, p₃,
p₄: the pressures at the SWL, at the sea bottom (extrapolated), at the base of the
upright section and at its crest; p_u: the uplift at the seaward edge of the base,
falling linearly to 0 at the heel)::

    η*  = 0.75 (1 + cos β) λ₁ H_max
    p₁  = ½ (1 + cos β) (λ₁ α₁ + λ₂ α₂ cos²β) ρ g H_max
    p₂  = p₁ / cosh(2πh/L)
    p₃  = α₃ p₁
    p₄  = p₁ (1 − h_c/η*) if η* > h_c, else 0
    p_u = ½ (1 + cos β) λ₃ α₁ α₃ ρ g H_max
    α₁  = 0.6 + ½ [(4πh/L) / sinh(4πh/L)]²
    α₂  = min{ (h_b − d)/(3 h_b) (H_max/d)², 2d/H_max }
    α₃  = 1 − (h'/h) [1 − 1/cosh(2πh/L)]

where h is the water depth in front of the breakwater, h_b the depth at 5 H_1/3
seaward of it (here default h), d the depth above the armour of the rubble
foundation (the berm), h' the depth of the base of the upright section below the
SWL, h_c the crest elevation above the SWL, β the angle between the wave direction
and the normal to the breakwater, λ₁, λ₂, λ₃ modification factors (1 for a plain
upright section) and L the wavelength at depth h of the design period (linear
dispersion, :func:`wavelength`). The pressure on the front face varies linearly from
0 at η* to p₁ at the SWL and to p₃ at the base (the line to p₂ at the sea bottom).

Resultants per metre (the integrals of this profile), with h_c* = min(η*, h_c): the horizontal
force P, its moment M_P about the base of the upright section, the uplift force U on a
base of width B and its moment M_U about the heel::

    P   = ½ (p₁ + p₃) h' + ½ (p₁ + p₄) h_c*
    M_P = (2p₁ + p₃) h'²/6 + ½ (p₁ + p₄) h' h_c* + (p₁ + 2p₄) h_c*²/6
    U   = ½ p_u B,   M_U = ⅔ U B

The extended formula (opt-in, ``impulsive=True``): Takahashi, Tanimoto & Shimosako (1994)
"A proposal of impulsive pressure coefficient for design of composite breakwaters",
Proc. Int. Conf. Hydro-Technical Eng. for Port and Harbor Construction, 489–504 (as
given in the CEM Part VI-5 and in Takahashi's "Design of vertical breakwaters", PARI
1996/2002, §4.3) replaces α₂ in p₁ by α* = max(α₂, α_I), the impulsive pressure
coefficient of a wave breaking on a high or wide berm of width B_M (the berm in front of
the upright section, at the depth d)::

    α_I  = α_I0 α_I1
    α_I0 = H_max/d if H_max <= 2d, else 2
    α_I1 = cos δ₂ / cosh δ₁ if δ₂ <= 0, else 1 / (cosh δ₁ cosh^½ δ₂)
    δ₁   = 20 δ₁₁ if δ₁₁ <= 0, else 15 δ₁₁
    δ₂   = 4.9 δ₂₂ if δ₂₂ <= 0, else 3 δ₂₂
    δ₁₁  = 0.93 (B_M/L − 0.12) + 0.36 (0.4 − d/h)
    δ₂₂  = −0.36 (B_M/L − 0.12) + 0.93 (0.4 − d/h)

η*, p₃ = α₃ p₁, p₄ and the uplift p_u (which has no α₂) follow as above.

**Range of validity** (checked by :func:`goda_pressure`, which refuses anything outside
with a :class:`GodaRangeError` naming the input and the range)::

    H_max > 0, T > 0, ρ > 0, g > 0
    0 < d <= h' <= h          the upright section stands on the mound, in the water
                              (Goda 2000 §4.2.2, Fig. 4.5; d > 0: α₂ has (H_max/d)²)
    h_b >= d                  α₂ >= 0: (h_b − d)/(3 h_b) < 0 would turn the mound's
                              effect into suction on the front (α₂ is an increase of
                              pressure by the mound, Goda 1974)
    h_c >= 0                  a crest above the SWL (submerged walls: other formulas)
    0 <= β < 90°, λ₁, λ₂, λ₃ >= 0
    H_max <= H_b              the design wave reaches the wall: no higher than the
                              breaking limit at the depth h_B = max(h, h_b)

with H_b Goda's breaker index (Goda 1970, "A synthesis of breaker indices", Trans. JSCE
2; Goda 2000 §3.6; re-examined in Goda 2010, Coastal Eng. J. 52(1) 71–106)::

    H_b = A L₀ {1 − exp[−1.5 (π h_B/L₀)(1 + 15 tan^(4/3) θ)]},  A = 0.17, L₀ = gT²/2π

taken at tan θ = 1/10, the steepest bottom slope of the data behind it (Goda 2010): the
most permissive limit, 0.17 L₀ in deep water (the steepness limit) and 1.36 h_B in
shallow water, so that only a wave that cannot exist is refused (H_max = 10 h is). Goda's
surf-zone formulas for H_max of random waves (2000 §3.6) can give more than this
regular-wave limit very near the shore (h_b/L₀ < 0.05 with steep waves); such a design
wave is refused too.

The wavelength solves ω² = g k tanh(k h) (:func:`wavelength`) for any period and depth
(no overflow: the hyperbolic functions of large arguments are taken in their decaying
forms, e.g. 1/cosh x = 2e^(−x)/(1 + e^(−2x)), so α₁ → 0.6, α₃ → 1 − h'/h and p₂ → 0 in
deep water).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

__all__ = ["GodaPressure", "GodaRangeError", "breaking_height", "goda_pressure",
           "impulsive_coefficient", "wavelength"]

BREAKER_SLOPE = 0.1
"""tan θ of Goda's breaker index in the breaking check: the steepest of its data."""


class GodaRangeError(ValueError):
    """An input of Goda's formula out of its range of validity.

    Attributes:
        key: The input (the name of the :func:`goda_pressure` argument, which is also
            the case file's key).
        problem: What is wrong, with the range.

    """

    def __init__(self, key: str, problem: str) -> None:
        super().__init__(f"{key}: {problem}")
        self.key = key
        self.problem = problem


def _sech(x: float) -> float:
    """1/cosh x without overflow (→ 0 for large |x|)."""
    e = math.exp(-abs(x))
    return 2.0 * e / (1.0 + e * e)


def _x_over_sinh(x: float) -> float:
    """The ratio x / sinh x without overflow (1 at x = 0, → 0 for large |x|)."""
    x = abs(x)
    if x < 1e-8:
        return 1.0
    if x < 1.0:
        return x / math.sinh(x)
    e = math.exp(-x)
    return 2.0 * x * e / (1.0 - e * e)


def wavelength(period: float, depth: float, gravity: float = 9.81) -> float:
    """Wavelength L (m) of linear waves: ω² = g k tanh(k h), L = 2π/k.

    Solved for y = k h from y tanh y = K, K = ω² h/g (tanh never overflows): Fenton &
    McKee's (1990) approximation y₀ = K / tanh(K^¾)^⅔ (within 1.7 %), then Newton's
    method kept inside the bracket [y_lo, y_lo / tanh y_lo], y_lo = max(K, √K) (F(y) =
    y tanh y − K is increasing, F(y_lo) <= 0 <= F(y_lo / tanh y_lo)), bisecting when a
    step leaves it; to round-off for any period and depth (deep water: y = K exactly
    once tanh K = 1; shallow: y → √K).

    Args:
        period: Wave period T (s).
        depth: Water depth h (m).
        gravity: g (m/s²).

    Raises:
        ValueError: A non-positive input, or one so extreme that ω² h/g is not a
            positive finite number.

    """
    if not (period > 0 and depth > 0 and gravity > 0):
        raise ValueError("period, depth and gravity must be > 0")
    ω = 2.0 * math.pi / period
    K = ω * ω * depth / gravity  # inf, not OverflowError, beyond the float range
    if not (K > 0 and math.isfinite(K)):
        raise ValueError(f"ω² h/g = {K:g} for T = {period:g} s, h = {depth:g} m: "
                         "out of the range of floating point")
    return 2.0 * math.pi * depth / _dispersion_root(float(K))


@functools.lru_cache(maxsize=256)
def _dispersion_root(K: float) -> float:
    """The root y = k h of y tanh y = K (K > 0 finite), for :func:`wavelength`.

    Cached: a storm's waves share one period, and the rigid-block Monte Carlo
    (:func:`breakwater.storms.montecarlo.expected_sliding`) evaluates Goda's formula,
    two wavelengths each, for every wave of every storm (2 × 10⁶ roots of a few
    distinct K for 1000 storms of 1000 waves).
    """
    lo = max(K, math.sqrt(K))
    hi = lo / math.tanh(lo)
    y = min(max(K / math.tanh(K**0.75) ** (2.0 / 3.0), lo), hi)
    for _ in range(200):
        th = math.tanh(y)
        f = y * th - K
        if f == 0.0:
            break
        if f < 0.0:
            lo = y
        else:
            hi = y
        df = th + y * (1.0 - th) * (1.0 + th)
        new = y - f / df
        if not lo < new < hi:
            new = 0.5 * (lo + hi)
        if abs(new - y) <= 4e-16 * y or hi - lo <= 4e-16 * hi:
            y = new
            break
        y = new
    return y


def breaking_height(period: float, depth: float, slope: float = BREAKER_SLOPE,
                    gravity: float = 9.81) -> float:
    """Goda's breaker index: the highest wave H_b (m) at a depth (module docstring).

    Args:
        period: Wave period T (s).
        depth: Water depth (m).
        slope: Bottom slope tan θ (default 1/10, the most permissive of its data).
        gravity: g (m/s²).

    """
    L0 = gravity * period**2 / (2.0 * math.pi)
    x = 1.5 * math.pi * depth / L0 * (1.0 + 15.0 * slope ** (4.0 / 3.0))
    return 0.17 * L0 * -math.expm1(-x)


def impulsive_coefficient(wave_height: float, depth: float, berm_depth: float,
                          berm_width: float, wavelength: float) -> float:
    """Takahashi et al.'s (1994) impulsive pressure coefficient α_I (module docstring).

    Args:
        wave_height: H_max (m).
        depth: Water depth h in front of the breakwater (m).
        berm_depth: d, depth above the armour of the berm (m).
        berm_width: B_M, width of the berm in front of the upright section (m).
        wavelength: L at the depth h (m).

    """
    shape = berm_width / wavelength - 0.12
    submergence = 0.4 - berm_depth / depth
    δ11 = 0.93 * shape + 0.36 * submergence
    δ22 = -0.36 * shape + 0.93 * submergence
    δ1 = 20.0 * δ11 if δ11 <= 0.0 else 15.0 * δ11
    δ2 = 4.9 * δ22 if δ22 <= 0.0 else 3.0 * δ22
    if δ2 <= 0.0:
        α_i1 = math.cos(δ2) * _sech(δ1)
    else:
        α_i1 = _sech(δ1) * math.sqrt(_sech(δ2))
    α_i0 = wave_height / berm_depth if wave_height <= 2.0 * berm_depth else 2.0
    return α_i0 * α_i1


@dataclass(frozen=True)
class GodaPressure:
    """The result of Goda's formula (SI units: m, Pa, N/m, N m/m).

    Attributes:
        wavelength: L at the depth h (m).
        alpha1, alpha2, alpha3: α₁, α₂, α₃.
        eta_star: η* (m above the SWL).
        p1, p2, p3, p4: Pressures at the SWL, the sea bottom, the base of the upright
            section and its crest (Pa).
        uplift: p_u at the seaward edge of the base (Pa).
        toe_depth: h' (m below the SWL).
        crest_height: h_c (m above the SWL).
        alpha_impulsive: α_I of the extended formula (None: Goda's formula, α* = α₂).

    """

    wavelength: float
    alpha1: float
    alpha2: float
    alpha3: float
    eta_star: float
    p1: float
    p2: float
    p3: float
    p4: float
    uplift: float
    toe_depth: float
    crest_height: float
    alpha_impulsive: float | None = None

    @property
    def alpha_star(self) -> float:
        """α* = max(α₂, α_I), the coefficient of p₁ (α₂ without the impulsive term)."""
        if self.alpha_impulsive is None:
            return self.alpha2
        return max(self.alpha2, self.alpha_impulsive)

    @property
    def wetted_crest(self) -> float:
        """h_c* = min(η*, h_c): the height of the loaded face above the SWL (m)."""
        return min(self.eta_star, self.crest_height)

    def front(self, z: float) -> float:
        """Pressure on the front face at elevation z above the SWL (Pa; 0 off the face)."""
        if z < -self.toe_depth or z > self.wetted_crest:
            return 0.0
        if z >= 0.0:
            return self.p1 * (1.0 - z / self.eta_star)
        return self.p1 + (self.p3 - self.p1) * (-z / self.toe_depth)

    def front_points(self) -> tuple[tuple[float, float], ...]:
        """(z, p) points of the front profile (z above the SWL), linear between them."""
        points = [(-self.toe_depth, self.p3), (0.0, self.p1)]
        if self.wetted_crest > 0.0:
            points.append((self.wetted_crest, self.p4))
        return tuple(points)

    @property
    def force(self) -> float:
        """Horizontal force P on the upright section (N/m)."""
        hc = self.wetted_crest
        return 0.5 * (self.p1 + self.p3) * self.toe_depth + 0.5 * (self.p1 + self.p4) * hc

    @property
    def moment(self) -> float:
        """Moment M_P of the horizontal force about the base of the upright section (N m/m)."""
        h1, hc, p1, p3, p4 = self.toe_depth, self.wetted_crest, self.p1, self.p3, self.p4
        return ((2 * p1 + p3) * h1**2 / 6 + 0.5 * (p1 + p4) * h1 * hc
                + (p1 + 2 * p4) * hc**2 / 6)

    def part(self, lo: float, hi: float) -> tuple[float, float]:
        """Force and moment (about the base, z = −h') of the profile on lo <= z <= hi.

        The exact integrals of the piecewise-linear profile over the part of the face
        between the elevations lo and hi (m above the SWL); ``part(-h', h_c*)`` is
        (:attr:`force`, :attr:`moment`).
        """
        force = moment = 0.0
        h1 = self.toe_depth
        pieces = ((-h1, 0.0, self.p3, self.p1), (0.0, self.wetted_crest, self.p1, self.p4))
        for z0, z1, q0, q1 in pieces:
            a, b = max(lo, z0), min(hi, z1)
            if not b > a:
                continue
            slope = (q1 - q0) / (z1 - z0)
            pa, pb = q0 + slope * (a - z0), q0 + slope * (b - z0)
            force += 0.5 * (pa + pb) * (b - a)
            # ∫ p (z + h') dz, exact by Simpson's rule (a quadratic integrand).
            mid = 0.5 * (a + b)
            pm = 0.5 * (pa + pb)
            moment += (b - a) / 6.0 * (pa * (a + h1) + 4.0 * pm * (mid + h1) + pb * (b + h1))
        return force, moment

    def uplift_force(self, width: float) -> float:
        """Uplift U = ½ p_u B on a base of width B (N/m)."""
        return 0.5 * self.uplift * width

    def uplift_moment(self, width: float) -> float:
        """Moment M_U = ⅔ U B of the uplift about the heel (N m/m)."""
        return 2.0 / 3.0 * self.uplift_force(width) * width


def goda_pressure(wave_height: float, period: float, depth: float, toe_depth: float,
                  berm_depth: float, crest_height: float, angle: float = 0.0,
                  breaking_depth: float | None = None,
                  factors: tuple[float, float, float] = (1.0, 1.0, 1.0),
                  density: float = 1025.0, gravity: float = 9.81, impulsive: bool = False,
                  berm_width: float | None = None) -> GodaPressure:
    """Goda's design wave pressures (see the module docstring for the equations).

    Args:
        wave_height: H_max (m).
        period: Period of the design wave (s).
        depth: Water depth h in front of the breakwater (m).
        toe_depth: h', depth of the base of the upright section below the SWL (m).
        berm_depth: d, depth above the armour of the foundation (m), <= h'.
        crest_height: h_c, crest elevation above the SWL (m).
        angle: β, wave incidence from the normal to the breakwater (degrees).
        breaking_depth: h_b, depth at 5 H_1/3 seaward (m); None: h.
        factors: λ₁, λ₂, λ₃.
        density: Water density ρ (kg/m³).
        gravity: g (m/s²).
        impulsive: The extended formula: α* = max(α₂, α_I) in p₁ (Takahashi et al. 1994).
        berm_width: B_M, width of the berm in front of the upright section (m); given
            exactly when ``impulsive``.

    Raises:
        GodaRangeError: An input outside the range of validity of the formula (module
            docstring), named with its range.

    """
    hb = depth if breaking_depth is None else breaking_depth
    _check_range(wave_height, period, depth, toe_depth, berm_depth, crest_height, angle,
                 hb, factors, density, gravity, impulsive, berm_width)
    λ1, λ2, λ3 = factors
    L = wavelength(period, depth, gravity)
    kh = 2.0 * math.pi * depth / L
    α1 = 0.6 + 0.5 * _x_over_sinh(2.0 * kh) ** 2
    α2 = min((hb - berm_depth) / (3.0 * hb) * (wave_height / berm_depth) ** 2,
             2.0 * berm_depth / wave_height)
    sech = _sech(kh)
    α3 = 1.0 - toe_depth / depth * (1.0 - sech)
    α_i = (impulsive_coefficient(wave_height, depth, berm_depth, berm_width, L)
           if berm_width is not None else None)
    α_star = α2 if α_i is None else max(α2, α_i)
    cb = math.cos(math.radians(angle))
    η = 0.75 * (1.0 + cb) * λ1 * wave_height
    ρgH = density * gravity * wave_height
    p1 = 0.5 * (1.0 + cb) * (λ1 * α1 + λ2 * α_star * cb**2) * ρgH
    p4 = p1 * (1.0 - crest_height / η) if η > crest_height else 0.0
    pu = 0.5 * (1.0 + cb) * λ3 * α1 * α3 * ρgH
    return GodaPressure(wavelength=L, alpha1=α1, alpha2=α2, alpha3=α3, eta_star=η, p1=p1,
                        p2=p1 * sech, p3=α3 * p1, p4=p4, uplift=pu, toe_depth=toe_depth,
                        crest_height=crest_height, alpha_impulsive=α_i)


def _check_range(wave_height: float, period: float, depth: float, toe_depth: float,
                 berm_depth: float, crest_height: float, angle: float, hb: float,
                 factors: tuple[float, ...], density: float, gravity: float,
                 impulsive: bool, berm_width: float | None) -> None:
    """Raise :class:`GodaRangeError` for an input outside the formula's range."""
    for name, value in (("wave_height", wave_height), ("period", period), ("depth", depth),
                        ("toe_depth", toe_depth), ("berm_depth", berm_depth),
                        ("breaking_depth", hb), ("density", density),
                        ("gravity", gravity)):
        if not (value > 0 and math.isfinite(value)):
            raise GodaRangeError(name, f"must be > 0 (got {value:g})")
    if not (crest_height >= 0 and math.isfinite(crest_height)):
        raise GodaRangeError("crest_height", f"h_c = {crest_height:g} m: must be >= 0 (the "
                             "crest above the still water level)")
    if toe_depth > depth:
        raise GodaRangeError("toe_depth", f"h' = {toe_depth:g} m must not exceed the depth "
                             f"h = {depth:g} m (range 0 < d <= h' <= h)")
    if berm_depth > toe_depth:
        raise GodaRangeError("berm_depth", f"d = {berm_depth:g} m must not exceed toe_depth "
                             f"h' = {toe_depth:g} m (range 0 < d <= h' <= h)")
    if hb < berm_depth:
        α2 = (hb - berm_depth) / (3.0 * hb) * (wave_height / berm_depth) ** 2
        raise GodaRangeError("breaking_depth", f"h_b = {hb:g} m is shallower than the berm "
                             f"depth d = {berm_depth:g} m: α₂ = {α2:.3g} < 0 would put "
                             f"suction on the front (range h_b >= d)")
    if not 0.0 <= angle < 90.0:
        raise GodaRangeError("angle", f"β = {angle:g}°: must be in [0, 90) degrees")
    if len(factors) != 3 or not all(f >= 0 and math.isfinite(f) for f in factors) \
            or not factors[0] > 0:
        raise GodaRangeError("factors", f"λ₁, λ₂, λ₃ = {list(factors)}: expected three "
                             "values, λ₁ > 0 (η* = 0.75 (1 + cos β) λ₁ H_max), λ₂, λ₃ >= 0")
    if impulsive and not (berm_width is not None and berm_width > 0
                          and math.isfinite(berm_width)):
        raise GodaRangeError("berm_width", f"B_M must be given (> 0) with impulsive "
                             f"(got {berm_width})")
    if not impulsive and berm_width is not None:
        raise GodaRangeError("berm_width", "is used only with impulsive (the extended "
                             "formula)")
    try:
        wavelength(period, depth, gravity)
    except ValueError as e:
        raise GodaRangeError("period", str(e)) from None
    at = max(depth, hb)
    limit = breaking_height(period, at, BREAKER_SLOPE, gravity)
    if wave_height > limit:
        raise GodaRangeError("wave_height", f"H_max = {wave_height:g} m exceeds the breaking "
                             f"limit H_b = {limit:.4g} m at the depth {at:g} m for T = "
                             f"{period:g} s (Goda's breaker index, bottom slopes up to "
                             f"1/10): range 0 < H_max <= {limit:.4g} m")
