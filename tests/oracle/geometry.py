"""Helical involute geometry of the gear pair and the tooth pairs in the zone of action.

Conventions (docs/model.md, section 2):

* Each gear's angle is positive in its own forward direction.  ``phi_p = 0`` with
  ``phi_w = 0`` puts the pinion tooth centreline on the line of centres, centred in the
  wheel's tooth space (teeth at the centre of the backlash).
* ``s`` is the roll coordinate along a transverse line of action, measured from the
  pinion's base-circle tangent point; at a contact ``s`` is the pinion's roll length
  (involute radius of curvature, transverse) ``rho_p`` and ``L - s`` the wheel's, where
  ``L = a sin(alpha_t)`` is the length between the two base tangent points (eq. 5, read as
  MODEL_NOTES section 2).
* ``flank = +1`` is the drive flank (pinion leads), ``flank = -1`` the coast flank.
  On the drive line of action the contacts travel towards larger ``s`` when the pinion turns
  forward, on the coast line towards smaller ``s``.
* A helical tooth pair touches along a straight contact line inclined at the base helix
  angle; across the face width it spans ``w = b tan(beta_b)`` of roll coordinate.  A pair is
  in the zone of action while that span overlaps the path of contact ``[s_start, s_end]``.
* The flanks are lead-crowned (``contact.crowning`` C_b, composite, along the contact normal):
  along its contact line a pair's gap grows parabolically from the face centre, C_b at the face
  ends.  A pair therefore touches at one point, the lowest point of its engaged contact line:
  the face centre (roll coordinate ``s_n``) while that lies in the path of contact, else the end
  of the path nearest to it, where the crown leaves the offset ``g = C_b (d / (w/2))^2`` (d the
  roll distance from the face centre).  Since eps_alpha >= 1, at least one pair always has its
  face centre in the path, so the flank's first contact is always at zero offset.
* ``contact.geometry`` 1 (the paper's) and 2 (line contact) take the flanks unmodified: every
  pair in the zone of action touches at the shared rigid approach (no offset) and stands for
  its engaged contact line ``[max(s_n - w/2, s_start), min(s_n + w/2, s_end)]``: its contact
  point is the line's centre, its length the line's (a roll distance d along the line is
  ``d / sin(beta_b)`` of line; a spur pair's line is the face width).
"""

from __future__ import annotations

import itertools
import math
from typing import Protocol

DRIVE = 1
COAST = -1

#: contact.geometry codes
LAYOUT_CROWNED = 0
LAYOUT_PAPER = 1
LAYOUT_LINE = 2
#: Samples of ln(r_y/r_x) along the path for the paper's eq. 6, and the relative margin the
#: range is widened by (the contact law is tabulated over it).
EQ6_RANGE_SAMPLES = 256
EQ6_RANGE_MARGIN = 0.01

#: Upper bound on the number of tooth pairs that can be in the zone of action at once.
#: The mesh unit outputs this many `pair[k].W` slots; a geometry needing more is rejected.
MAX_PAIR_SLOTS = 8

#: Roll distance [m] under which a breakpoint counts as reached (far below any physical
#: length, above the rounding of roll coordinates of a long run: ~1e-14 m at 100 m of roll).
BREAKPOINT_TOLERANCE = 1e-12


class PairDimensions(Protocol):
    """What the geometry reads of the parameters (``parameters.MeshParameters``: the gear.*
    and contact.crowning parameters, SI units)."""

    z_pinion: int
    z_wheel: int
    m_n: float
    alpha_n: float
    beta: float
    addendum: float
    b: float
    backlash: float
    crowning: float
    contact_geometry: int


class HelicalPairGeometry:
    """Geometry of an unshifted helical involute pair.

    All lengths in m, angles in rad.  Raises ValueError for pairs that undercut, interfere,
    have a transverse contact ratio below 1 or need more than ``MAX_PAIR_SLOTS`` pair slots.
    """

    def __init__(self, p: PairDimensions):
        self.z_pinion = p.z_pinion
        self.z_wheel = p.z_wheel
        self.ratio = p.z_pinion / p.z_wheel  # wheel speed / pinion speed in rigid mesh
        # Transverse pressure angle and base helix angle (MODEL_NOTES section 4).
        self.alpha_t = math.atan(math.tan(p.alpha_n) / math.cos(p.beta))
        self.beta_b = math.asin(math.sin(p.beta) * math.cos(p.alpha_n))
        self.m_t = p.m_n / math.cos(p.beta)
        # Pitch, base and tip radii; addendum h_a m_n, no profile shift.
        self.r_pinion = 0.5 * p.z_pinion * self.m_t
        self.r_wheel = 0.5 * p.z_wheel * self.m_t
        self.centre_distance = self.r_pinion + self.r_wheel
        self.rb_pinion = self.r_pinion * math.cos(self.alpha_t)
        self.rb_wheel = self.r_wheel * math.cos(self.alpha_t)
        self.ra_pinion = self.r_pinion + p.addendum * p.m_n
        self.ra_wheel = self.r_wheel + p.addendum * p.m_n
        # Line of action between the base tangent points, and the path of contact on it.
        self.line_length = self.centre_distance * math.sin(self.alpha_t)
        self.s_start = self.line_length - math.sqrt(self.ra_wheel**2 - self.rb_wheel**2)
        self.s_end = math.sqrt(self.ra_pinion**2 - self.rb_pinion**2)
        self.s_pitch = self.rb_pinion * math.tan(self.alpha_t)
        self.base_pitch = 2.0 * math.pi * self.rb_pinion / p.z_pinion  # transverse, p_bt
        self.eps_alpha = (self.s_end - self.s_start) / self.base_pitch
        self.eps_beta = p.b * math.sin(p.beta) / (math.pi * p.m_n)
        self.eps_gamma = self.eps_alpha + self.eps_beta
        # Transverse extent of one contact line across the face (= eps_beta * p_bt).  A span
        # below the roll resolution is a spur pair's contact line (and its square would
        # underflow in the crown offset below).
        self.line_span = p.b * math.tan(self.beta_b)
        if self.line_span < BREAKPOINT_TOLERANCE:
            self.line_span = 0.0
        # Lead crowning: gap g = crown_factor * d^2 at roll distance d from the face centre
        # (C_b at d = w/2), and the flank radius along the contact line it implies (eq. 6 read
        # as crowning): a distance l along the line is l sin(beta_b) of roll, and the axial face
        # end lies at l = b / (2 cos beta_b), so r_y = (b / (2 cos beta_b))^2 / (2 C_b).
        self.crowning = p.crowning
        half_span = 0.5 * self.line_span
        self.crown_factor = p.crowning / (half_span * half_span) if half_span > 0.0 else 0.0
        half_line = 0.5 * p.b / math.cos(self.beta_b)
        self.r_y = half_line * half_line / (2.0 * p.crowning)
        # Rigid-body kinematics onto the tooth normal: delta = cos(beta_b)*(rb_p phi_p - rb_w phi_w)
        self.normal_factor = math.cos(self.beta_b)
        # Direction cosines of the normal force: cos(beta_b) cos(alpha_t) tangential,
        # cos(beta_b) sin(alpha_t) radial, sin(beta_b) axial.
        self.cos_alpha_t = math.cos(self.alpha_t)
        self.sin_alpha_t = math.sin(self.alpha_t)
        self.sin_beta_b = math.sin(self.beta_b)
        self.half_backlash = 0.5 * p.backlash
        self.layout = getattr(p, "contact_geometry", LAYOUT_CROWNED)
        self.face_width = p.b
        # Roll coordinate of the reference pair at phi_p = 0 (tooth centreline on the line of
        # centres: the flank is a quarter base pitch ahead of the pitch point), both flanks.
        self.flank_phase = self.s_pitch + 0.25 * self.base_pitch
        self._check(p)
        self._breakpoints = self._roll_breakpoints()

    # ------------------------------------------------------------------ validation
    def _check(self, p: PairDimensions) -> None:
        sin2 = math.sin(self.alpha_t) ** 2
        # Undercut limit of a rack cutter whose dedendum matches the addendum h_a m_n.
        z_min = 2.0 * p.addendum * math.cos(p.beta) / sin2
        for name, z in (("gear.z_pinion", p.z_pinion), ("gear.z_wheel", p.z_wheel)):
            if z < z_min:
                raise ValueError(
                    f"parameter '{name}' = {z} undercuts with gear.alpha_n = "
                    f"{math.degrees(p.alpha_n):.4g} deg and gear.beta = "
                    f"{math.degrees(p.beta):.4g} deg; "
                    f"allowed: {name} >= {math.ceil(z_min - 1e-9)} (2 cos(beta)/sin^2(alpha_t) "
                    f"* gear.h_a = {z_min:.4g})")
        if self.s_start <= 0.0 or self.s_end >= self.line_length:
            raise ValueError(
                "tip interference: the path of contact leaves the line of action "
                f"(s_start = {self.s_start:.4g} m, s_end = {self.s_end:.4g} m, line length "
                f"{self.line_length:.4g} m) for gear.z_pinion = {p.z_pinion}, gear.z_wheel = "
                f"{p.z_wheel}; allowed: 0 < s_start < s_end < line length")
        if self.eps_alpha < 1.0:
            raise ValueError(
                f"transverse contact ratio eps_alpha = {self.eps_alpha:.4f} below 1 for "
                f"gear.z_pinion = {p.z_pinion}, gear.z_wheel = {p.z_wheel}, gear.h_a = "
                f"{p.addendum:.4g}, gear.alpha_n = {math.degrees(p.alpha_n):.4g} deg, gear.beta = "
                f"{math.degrees(p.beta):.4g} deg; allowed: eps_alpha >= 1")
        if self.layout == LAYOUT_PAPER:
            R_p = math.sqrt(self.rb_pinion**2 + self.s_end**2)
            R_w = math.sqrt(self.rb_wheel**2 + (self.line_length - self.s_end) ** 2)
            if not R_w > R_p:
                raise ValueError(
                    f"parameter 'contact.geometry' = {self.layout} (the paper's eq. 6, r_y = "
                    "R_p R_w / (R_w - R_p)) needs the wheel's radius at every contact point "
                    f"larger than the pinion's; with gear.z_pinion = {p.z_pinion}, "
                    f"gear.z_wheel = {p.z_wheel} it is {R_w * 1e3:.6g} mm against "
                    f"{R_p * 1e3:.6g} mm at the pinion tip; allowed: contact.geometry = 0 or 2, "
                    "or a wheel with more teeth")
        if self.max_pairs > MAX_PAIR_SLOTS:
            b_max = (MAX_PAIR_SLOTS - self.eps_alpha) * math.pi * p.m_n / max(
                math.sin(p.beta), 1e-300)
            raise ValueError(
                f"parameter 'gear.b' = {p.b!r} gives a total contact ratio eps_gamma = "
                f"{self.eps_gamma:.4g}, needing {self.max_pairs} pair slots; at most "
                f"{MAX_PAIR_SLOTS} are available; allowed: gear.b < {b_max:.4g} m")

    @property
    def max_pairs(self) -> int:
        """Largest number of pairs that can be in the zone of action at once."""
        return math.floor(self.eps_gamma) + 1

    # ------------------------------------------------------------------ pairs
    def flank_roll(self, flank: int, phi_p: float) -> float:
        """Roll coordinate ``u`` of pair 0's contact-line centre for pinion angle ``phi_p``.

        Pair ``n`` sits at ``s_n = u - n * base_pitch``.
        """
        return self.flank_phase + flank * self.rb_pinion * phi_p

    def pairs(self, flank: int, phi_p: float) -> list[tuple[int, float, float, float]]:
        """Tooth pairs in the zone of action on ``flank`` at pinion angle ``phi_p``.

        Returns ``(slot, s, g, dg)`` per pair: the slot (pair number modulo
        ``MAX_PAIR_SLOTS``, so a slot follows one pair through its passage), the roll
        coordinate ``s`` of its contact point [m] (the lowest point of its engaged contact
        line), the crown offset ``g`` of that point [m] (the pair touches when the flank's
        penetration exceeds it) and ``dg = dg/ds_n`` [1], the offset's rate per unit roll of
        the pair's face centre.
        """
        return self.pairs_at_roll(self.flank_roll(flank, phi_p))

    def pairs_at_roll(self, u: float) -> list[tuple[int, float, float, float]]:
        """As :meth:`pairs`, from the roll coordinate ``u`` of :meth:`flank_roll`."""
        pb = self.base_pitch
        half = 0.5 * self.line_span
        s0, s1 = self.s_start, self.s_end
        k = self.crown_factor
        n_lo = math.floor((u - s1 - half) / pb) + 1
        n_hi = math.ceil((u - s0 + half) / pb) - 1
        if self.layout != LAYOUT_CROWNED:
            return [(slot, s, 0.0, 0.0) for slot, s, _ in self.lines_at_roll(u)]
        out = []
        for n in range(n_lo, n_hi + 1):
            s = u - n * pb  # roll coordinate of the pair's face centre
            if half > 0.0:
                if s + half > s0 and s - half < s1:
                    if s < s0:
                        d = s0 - s
                        out.append((n % MAX_PAIR_SLOTS, s0, k * d * d, -2.0 * k * d))
                    elif s > s1:
                        d = s - s1
                        out.append((n % MAX_PAIR_SLOTS, s1, k * d * d, 2.0 * k * d))
                    else:
                        out.append((n % MAX_PAIR_SLOTS, s, 0.0, 0.0))
            elif s0 < s < s1:
                out.append((n % MAX_PAIR_SLOTS, s, 0.0, 0.0))
        return out

    def lines(self, flank: int, phi_p: float) -> list[tuple[int, float, float]]:
        """Unmodified flanks: ``(slot, s, length)`` of every pair in the zone of action, its
        contact point ``s`` the centre of its engaged contact line, ``length`` [m] the line's
        length."""
        return self.lines_at_roll(self.flank_roll(flank, phi_p))

    def lines_at_roll(self, u: float) -> list[tuple[int, float, float]]:
        """As :meth:`lines`, from the roll coordinate ``u`` of :meth:`flank_roll`."""
        pb = self.base_pitch
        half = 0.5 * self.line_span
        s0, s1 = self.s_start, self.s_end
        n_lo = math.floor((u - s1 - half) / pb) + 1
        n_hi = math.ceil((u - s0 + half) / pb) - 1
        out = []
        for n in range(n_lo, n_hi + 1):
            s = u - n * pb  # the pair's face centre
            if half > 0.0:
                if not (s + half > s0 and s - half < s1):
                    continue
                lo, hi = max(s - half, s0), min(s + half, s1)
                length = (hi - lo) / self.sin_beta_b
            else:
                if not s0 < s < s1:
                    continue
                lo = hi = s
                length = self.face_width
            out.append((n % MAX_PAIR_SLOTS, min(max(0.5 * (lo + hi), s0), s1), length))
        return out

    def _roll_breakpoints(self) -> tuple[float, ...]:
        """Roll coordinates (mod base pitch) of a pair's face centre where the pair enters or
        leaves the zone of action (s_start - w/2, s_end + w/2) or its contact point starts or
        stops following the face centre (s_start, s_end); between them every pair quantity
        is a smooth function of the pinion angle."""
        half = 0.5 * self.line_span
        if self.layout == LAYOUT_CROWNED:
            raw = {self.s_start - half, self.s_start, self.s_end, self.s_end + half}
        else:  # where an end of the engaged line starts or stops following the path's end
            raw = {self.s_start - half, self.s_start + half, self.s_end - half,
                   self.s_end + half}
        return tuple(sorted(v % self.base_pitch for v in raw))

    def next_breakpoint(self, u_a: float, u_b: float) -> float | None:
        """First roll coordinate of a breakpoint between ``u_a`` and ``u_b`` (in the direction
        of travel), or None.  Breakpoints within ``BREAKPOINT_TOLERANCE`` of ``u_a`` are
        behind us: the previous substep ended on them."""
        if u_a == u_b:
            return None
        pb = self.base_pitch
        tol = BREAKPOINT_TOLERANCE
        best = None
        if u_b > u_a:
            for bp in self._breakpoints:
                v = bp + (math.floor((u_a + tol - bp) / pb) + 1) * pb
                if v < u_b and (best is None or v < best):
                    best = v
        else:
            for bp in self._breakpoints:
                v = bp + (math.ceil((u_a - tol - bp) / pb) - 1) * pb
                if v > u_b and (best is None or v > best):
                    best = v
        return best

    # ------------------------------------------------------------------ radii
    def normal_radii(self, s: float) -> tuple[float, float, float]:
        """Principal radii in the normal plane at roll coordinate ``s`` (eq. 3-5 as read in
        MODEL_NOTES section 2): the involute radius of curvature is the roll length, and a
        helicoid's normal-section radius is the transverse one over cos(beta_b).

        Returns ``(r_pinion, r_wheel, r_x)`` in m with ``r_x = r_p r_w / (r_p + r_w)``.
        """
        c = self.normal_factor
        rp = s / c
        rw = (self.line_length - s) / c
        return rp, rw, rp * rw / (rp + rw)

    def radius_y_eq6(self, s: float) -> float:
        """r_y of eq. 6 at roll coordinate ``s`` [m]: the gears' radii at the contact point
        (eq. 4's sqrt(R_b^2 + rho^2)) with the wheel's counted concave,
        1/r_y = 1/R_p - 1/R_w (the printed denominator R_p - R_w would make r_y negative for a
        wheel larger than the pinion)."""
        R_p = math.sqrt(self.rb_pinion**2 + s * s)
        R_w = math.sqrt(self.rb_wheel**2 + (self.line_length - s) ** 2)
        if R_w == R_p:  # (equal radii: no curvature difference, as IEEE division gives)
            return math.inf
        return R_p * R_w / (R_w - R_p)

    def radius_ratio_range(self) -> tuple[float, float]:
        """Bounds of ln(R/r), R and r the larger and smaller of r_x and r_y, over the contact
        points the path of contact allows (s in [s_start, s_end]): r_y the crown's, or for the
        paper's eq. 6 (varying along the path) from EQ6_RANGE_SAMPLES + 1 samples, widened by
        EQ6_RANGE_MARGIN of the range at both ends."""
        if self.layout == LAYOUT_PAPER:
            span = self.s_end - self.s_start
            v = [math.log(self.radius_y_eq6(s) / self.normal_radii(s)[2])
                 for s in (self.s_start + span * k / EQ6_RANGE_SAMPLES
                           for k in range(EQ6_RANGE_SAMPLES + 1))]
            lo, hi = min(v), max(v)
            margin = EQ6_RANGE_MARGIN * (hi - lo)
            lo, hi = lo - margin, hi + margin
            crosses = any((a > 0) != (b > 0) for a, b in itertools.pairwise(v))
            return (0.0 if crosses or lo <= 0.0 <= hi else min(abs(lo), abs(hi)),
                    max(abs(lo), abs(hi)))
        samples = [self.s_start, self.s_end]
        mid = 0.5 * self.line_length  # r_x(s) = s (L - s) / (L cos beta_b) peaks there
        if self.s_start < mid < self.s_end:
            samples.append(mid)
        r_x = [self.normal_radii(s)[2] for s in samples]
        r_lo, r_hi = min(r_x), max(r_x)
        candidates = [abs(math.log(self.r_y / r)) for r in (r_lo, r_hi)]
        if r_lo <= self.r_y <= r_hi:
            candidates.append(0.0)
        return min(candidates), max(candidates)

    def summary(self) -> dict[str, float]:
        """Derived quantities of the pair, SI units, for reports and documentation."""
        return {
            "alpha_t [rad]": self.alpha_t,
            "beta_b [rad]": self.beta_b,
            "centre distance [m]": self.centre_distance,
            "pitch radius pinion [m]": self.r_pinion,
            "pitch radius wheel [m]": self.r_wheel,
            "base radius pinion [m]": self.rb_pinion,
            "base radius wheel [m]": self.rb_wheel,
            "tip radius pinion [m]": self.ra_pinion,
            "tip radius wheel [m]": self.ra_wheel,
            "transverse base pitch [m]": self.base_pitch,
            "eps_alpha [1]": self.eps_alpha,
            "eps_beta [1]": self.eps_beta,
            "eps_gamma [1]": self.eps_gamma,
            "flank radius along the contact line r_y [m]": self.r_y,
        }
