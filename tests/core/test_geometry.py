"""Helical involute geometry: textbook identities and the reference pair."""

import math

import numpy as np
import pytest

from drive_rattle.geometry import COAST, DRIVE, MAX_PAIR_SLOTS, HelicalPairGeometry
from drive_rattle.parameters import DEG, MeshParameters


@pytest.fixture(scope="module")
def geo():
    return HelicalPairGeometry(MeshParameters())


@pytest.mark.parametrize("beta_deg", [0.0, 10.0, 27.75, 45.0])
def test_helical_identities(beta_deg):
    p = MeshParameters(beta=beta_deg * DEG, z_pinion=30, z_wheel=45)
    g = HelicalPairGeometry(p)
    assert math.isclose(math.tan(g.alpha_t), math.tan(p.alpha_n) / math.cos(p.beta))
    assert math.isclose(math.sin(g.beta_b), math.sin(p.beta) * math.cos(p.alpha_n))
    assert math.isclose(math.cos(g.alpha_t) * math.cos(g.beta_b),
                        math.cos(p.alpha_n) * math.cos(p.beta))
    assert math.isclose(g.rb_pinion, g.r_pinion * math.cos(g.alpha_t))
    # Base pitches: transverse and normal, p_bn = p_bt cos(beta_b) = pi m_n cos(alpha_n).
    assert math.isclose(g.base_pitch * math.cos(g.beta_b), math.pi * p.m_n * math.cos(p.alpha_n))
    # Pitch point: roll lengths at the pitch point are in the ratio of the base radii.
    assert math.isclose(g.s_pitch / (g.line_length - g.s_pitch), g.rb_pinion / g.rb_wheel)


def test_reference_pair(geo):
    # MODEL_NOTES section 3: centre distance 75.0 mm, eps_gamma ~ 3.
    assert geo.centre_distance == pytest.approx(75.0e-3, abs=0.01e-3)
    assert geo.ratio == pytest.approx(20 / 39)
    assert geo.eps_beta == pytest.approx(25 * math.sin(27.75 * DEG) / (math.pi * 2.25))
    assert geo.eps_gamma == pytest.approx(3.0, abs=0.05)
    assert geo.max_pairs == 4


def test_transverse_contact_ratio_from_path_of_contact(geo):
    # Textbook form in terms of the tip and base radii and centre distance.
    eps = (math.sqrt(geo.ra_pinion**2 - geo.rb_pinion**2)
           + math.sqrt(geo.ra_wheel**2 - geo.rb_wheel**2)
           - geo.centre_distance * math.sin(geo.alpha_t)) / (
        math.pi * 2.25e-3 * math.cos(geo.alpha_t) / math.cos(27.75 * DEG))
    assert geo.eps_alpha == pytest.approx(eps, rel=1e-12)


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_pairs_in_zone_average_to_contact_ratios(geo, flank):
    # Over one base pitch of roll, the mean number of pairs in the zone of action is
    # eps_gamma, and the mean number touching at zero crown offset (face centre inside the
    # path of contact) is eps_alpha; since eps_alpha >= 1 there is always at least one.
    phis = np.linspace(0.0, geo.base_pitch / geo.rb_pinion, 20001)[:-1]
    counts = [len(geo.pairs(flank, phi)) for phi in phis]
    centred = [sum(1 for _, _, g, _ in geo.pairs(flank, phi) if g == 0.0) for phi in phis]
    assert np.mean(counts) == pytest.approx(geo.eps_gamma, abs=2e-3)
    assert np.mean(centred) == pytest.approx(geo.eps_alpha, abs=2e-3)
    assert min(counts) == 3 and max(counts) == 4  # 3-4 pairs in the zone of action
    assert min(centred) >= 1


def test_pairs_stay_in_path_of_contact_and_slots_are_unique(geo):
    for phi in np.linspace(-3.0, 3.0, 997):
        pairs = geo.pairs(DRIVE, phi)
        slots = [slot for slot, _, _, _ in pairs]
        assert len(set(slots)) == len(slots)
        assert all(0 <= s < MAX_PAIR_SLOTS for s in slots)
        for _, s, g, _ in pairs:
            assert geo.s_start <= s <= geo.s_end
            assert 0.0 <= g <= geo.crowning * (1 + 1e-12)


def test_crown_offsets_follow_the_crowning_parabola(geo):
    # r_y from the crown: a crown drop C_b at the face end, l = b / (2 cos beta_b) along the
    # contact line, is l^2 / (2 r_y).
    half_line = 0.5 * 25e-3 / math.cos(geo.beta_b)
    assert half_line**2 / (2 * geo.r_y) == pytest.approx(geo.crowning, rel=1e-12)
    half = 0.5 * geo.line_span
    for phi in np.linspace(0.0, geo.base_pitch / geo.rb_pinion, 211):
        u = geo.flank_roll(DRIVE, phi)
        for slot, s, g, dg in geo.pairs(DRIVE, phi):
            # The pair number: the one of this slot whose face centre is nearest the
            # contact point (clamped contact points lie within w/2 < p_bt of it).
            near = round((u - s) / geo.base_pitch)
            n = next(k for k in (near - 1, near, near + 1) if k % MAX_PAIR_SLOTS == slot)
            centre = u - n * geo.base_pitch
            d = max(geo.s_start - centre, centre - geo.s_end, 0.0)
            assert g == pytest.approx(geo.crowning * (d / half) ** 2, rel=1e-9, abs=1e-18)
            # dg is the slope of the offset against the face centre's roll coordinate.
            e = 1e-9
            g_plus = dict((k, gg) for k, _, gg, _ in geo.pairs_at_roll(u + e))
            g_minus = dict((k, gg) for k, _, gg, _ in geo.pairs_at_roll(u - e))
            if slot in g_plus and slot in g_minus:
                assert dg == pytest.approx((g_plus[slot] - g_minus[slot]) / (2 * e),
                                           rel=1e-4, abs=1e-9)


def test_radius_ratio_range_bounds_every_contact_point(geo):
    lo, hi = geo.radius_ratio_range()
    for s in np.linspace(geo.s_start, geo.s_end, 101):
        r_x = geo.normal_radii(s)[2]
        assert lo - 1e-12 <= abs(math.log(geo.r_y / r_x)) <= hi + 1e-12


def test_drive_contacts_travel_towards_pinion_tip_coast_towards_root(geo):
    dphi = 1e-4
    (slot0, s0, _, _), = [p for p in geo.pairs(DRIVE, 0.0) if p[2] == 0.0][:1]
    s1 = dict((slot, s) for slot, s, _, _ in geo.pairs(DRIVE, dphi))[slot0]
    assert s1 > s0
    (slot0, s0, _, _), = [p for p in geo.pairs(COAST, 0.0) if p[2] == 0.0][:1]
    s1 = dict((slot, s) for slot, s, _, _ in geo.pairs(COAST, dphi))[slot0]
    assert s1 < s0


def test_breakpoints_bound_smooth_intervals(geo):
    u = geo.flank_roll(DRIVE, 0.0)
    bp = geo.next_breakpoint(u, u + 2 * geo.base_pitch)
    assert u < bp < u + geo.base_pitch
    # No breakpoint strictly between u and bp; the pair set is the same on both sides of u.
    assert geo.next_breakpoint(u, bp - 1e-9) is None
    assert geo.next_breakpoint(u + 2 * geo.base_pitch, u) is not None


def test_normal_radii(geo):
    rp, rw, rx = geo.normal_radii(geo.s_pitch)
    # At the pitch point the transverse roll lengths are r sin(alpha_t).
    c = math.cos(geo.beta_b)
    assert rp == pytest.approx(geo.r_pinion * math.sin(geo.alpha_t) / c)
    assert rw == pytest.approx(geo.r_wheel * math.sin(geo.alpha_t) / c)
    assert rx == pytest.approx(1 / (1 / rp + 1 / rw))
