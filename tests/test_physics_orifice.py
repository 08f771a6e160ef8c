"""Compressible orifice flow (thesis eq 4.1.1-4.1.9) and the ISO 6358 form."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import K_AIR, R_AIR
from pneumaquad.core.physics.orifice import (
    ISO_REFERENCE_DENSITY,
    ISO_REFERENCE_TEMPERATURE,
    area_to_sonic_conductance,
    iso6358_flux,
    iso6358_mass_flow,
    orifice_coefficients,
    orifice_flux,
    orifice_mass_flow,
)

CRITICAL = 0.528  # eq 4.1.4
LAMINAR = 0.999  # shipped laminar_pressure_ratio
C1, C2 = orifice_coefficients(K_AIR, R_AIR)
PS = (50.3 + 14.7) * 6894.76  # App. B.1.1 l.24-27, 78
AREA = 1.5e-7  # an equivalent area cd·A [m^2]


def psi(pu: float, pd: float, tu: float = 298.0, laminar: float = LAMINAR) -> float:
    return orifice_flux(pu, pd, tu, K_AIR, C1, C2, CRITICAL, laminar)


def flow(pa, pb, ta=298.0, tb=298.0, area=AREA) -> float:
    return orifice_mass_flow(area, pa, pb, ta, tb, K_AIR, C1, C2, CRITICAL, LAMINAR)


# --- constants ---------------------------------------------------------------------------


def test_flow_constants_match_eq_4_1_8_and_4_1_9() -> None:
    k, r = 1.4, 287.0
    c1_thesis = math.sqrt(2 * k / (r * (k - 1)))  # eq 4.1.8, App. B.1.1 l.35
    c2_thesis = math.sqrt(k / (r * ((k + 1) / 2) ** ((k + 1) / (k - 1))))  # eq 4.1.9, l.36
    c1, c2 = orifice_coefficients(k, r)
    assert c1 == pytest.approx(c1_thesis, rel=1e-12)
    assert c2 == pytest.approx(c2_thesis, rel=1e-12)
    assert c1 == pytest.approx(0.1562, abs=5e-5)
    assert c2 == pytest.approx(0.04042, abs=5e-6)


def test_choked_constant_is_the_maximum_of_the_unchoked_law() -> None:
    """C2 is the unchoked law (4.1.5) at the true critical ratio (2/(k+1))^(k/(k-1))."""
    k = K_AIR
    r_star = (2 / (k + 1)) ** (k / (k - 1))
    assert r_star == pytest.approx(0.528, abs=5e-4)  # eq 4.1.4
    unchoked = C1 * r_star ** (1 / k) * math.sqrt(1 - r_star ** ((k - 1) / k))
    assert unchoked == pytest.approx(C2, rel=1e-12)


# --- Psi ---------------------------------------------------------------------------------


def test_psi_unchoked_follows_eq_4_1_5() -> None:
    k = K_AIR
    for ratio in (0.6, 0.8, 0.95, 0.99):
        pu, tu = PS, 310.0
        pd = ratio * pu
        expected = (
            C1 * pu / math.sqrt(tu) * ratio ** (1 / k) * math.sqrt(1 - ratio ** ((k - 1) / k))
        )
        assert psi(pu, pd, tu) == pytest.approx(expected, rel=1e-12)


def test_psi_choked_follows_eq_4_1_6() -> None:
    for ratio in (0.0, 0.1, 0.3, 0.5, 0.528):
        assert psi(PS, ratio * PS, 280.0) == pytest.approx(C2 * PS / math.sqrt(280.0), rel=1e-12)


def test_psi_continuous_at_the_critical_ratio() -> None:
    below = psi(PS, (CRITICAL - 1e-9) * PS)
    above = psi(PS, (CRITICAL + 1e-9) * PS)
    assert above == pytest.approx(below, rel=1e-6)
    # 0.528 is the rounded critical ratio; the two laws meet within 1e-6 there.
    assert psi(PS, 0.5281 * PS) == pytest.approx(psi(PS, 0.528 * PS), rel=1e-5)


def test_choked_flux_independent_of_downstream_pressure() -> None:
    values = [psi(PS, pd) for pd in np.linspace(0.0, CRITICAL * PS, 17)]
    assert np.ptp(values) == 0.0


def test_psi_zero_at_equal_pressures_and_monotone_in_pressure_ratio() -> None:
    assert psi(PS, PS) == 0.0
    ratios = np.linspace(0.0, 1.0, 4001)
    values = np.array([psi(PS, r * PS) for r in ratios])
    assert values[-1] == 0.0
    assert np.all(np.diff(values) <= 0.0)  # less flux as the downstream pressure rises
    # the laminar end (ratio > 0.999) joins the eq 4.1.5 branch continuously
    assert psi(PS, (LAMINAR + 1e-12) * PS) == pytest.approx(psi(PS, LAMINAR * PS), rel=1e-6)


def test_psi_scales_with_upstream_pressure_over_sqrt_temperature() -> None:
    for ratio in (0.3, 0.7, 0.98):
        base = psi(PS, ratio * PS, 298.0)
        assert psi(2 * PS, 2 * ratio * PS, 298.0) == pytest.approx(2 * base, rel=1e-12)
        assert psi(PS, ratio * PS, 4 * 298.0) == pytest.approx(base / 2, rel=1e-12)


# --- signed mass flow ------------------------------------------------------------------


def test_mass_flow_is_area_times_psi() -> None:
    assert flow(PS, 2e5) == pytest.approx(AREA * C2 * PS / math.sqrt(298.0), rel=1e-12)
    assert flow(PS, 2e5, area=0.0) == 0.0


def test_mass_flow_antisymmetric_and_uses_upstream_temperature() -> None:
    for pa, pb in ((PS, 1.1e5), (PS, 0.8 * PS), (2.1e5, 2.0e5), (1.2e5, 4e5)):
        ta, tb = 250.0, 400.0
        forward = flow(pa, pb, ta, tb)
        backward = flow(pb, pa, tb, ta)
        assert backward == -forward
        upstream_t = ta if pa > pb else tb
        hi, lo = max(pa, pb), min(pa, pb)
        magnitude = AREA * psi(hi, lo, upstream_t)
        assert abs(forward) == pytest.approx(magnitude, rel=1e-12)
        assert np.sign(forward) == np.sign(pa - pb)
        # the downstream temperature does not enter
        if pa > pb:
            assert flow(pa, pb, ta, 1000.0) == forward
        else:
            assert flow(pa, pb, 1000.0, tb) == forward


def test_mass_flow_zero_at_equal_pressures() -> None:
    for p in (1e5, 3e5, PS):
        assert flow(p, p, 250.0, 350.0) == 0.0


def test_mass_flow_monotone_in_pressure_difference() -> None:
    pb = 2.5e5
    pas = np.linspace(0.5e5, 6e5, 2001)
    values = np.array([flow(pa, pb) for pa in pas])
    assert np.all(np.diff(values) >= 0.0)  # constant where choked either way
    unchoked = (pas > pb * CRITICAL) & (pas < pb / CRITICAL)
    assert np.all(np.diff(values[unchoked]) > 0.0)  # strictly increasing through zero
    assert values[0] < 0.0 < values[-1]


# --- ISO 6358 --------------------------------------------------------------------------

B = 0.3
CONDUCTANCE = 0.25e-8  # 0.25 dm^3/(s bar) in m^3/(s Pa)


def iso(pa, pb, ta=298.0, tb=298.0, c=CONDUCTANCE, b=B) -> float:
    return iso6358_mass_flow(c, pa, pb, ta, tb, b, LAMINAR)


def test_iso_reference_atmosphere_is_iso_8778() -> None:
    assert abs(ISO_REFERENCE_TEMPERATURE - 293.15) < 1e-12
    assert abs(ISO_REFERENCE_DENSITY - 1.185) < 1e-3


def test_iso_choked_flow_closed_form() -> None:
    for tu in (260.0, 298.0, 330.0):
        expected = CONDUCTANCE * 1.185 * PS * math.sqrt(293.15 / tu)
        for ratio in (0.0, 0.1, B):
            assert iso(PS, ratio * PS, tu) == pytest.approx(expected, rel=1e-12)


def test_iso_subsonic_ellipse_zero_at_one_and_continuous_at_b() -> None:
    choked = iso(PS, 0.0)
    for ratio in (0.4, 0.6, 0.9):
        shape = (ratio - B) / (1 - B)
        assert iso(PS, ratio * PS) == pytest.approx(choked * math.sqrt(1 - shape**2), rel=1e-12)
    assert iso(PS, PS) == 0.0
    assert iso(PS, (B + 1e-9) * PS) == pytest.approx(choked, rel=1e-6)
    ratios = np.linspace(0.0, 1.0, 2001)
    values = np.array([iso6358_flux(PS, r * PS, 298.0, B, LAMINAR) for r in ratios])
    assert np.all(np.diff(values) <= 0.0)
    assert values[-1] == 0.0


def test_iso_antisymmetric_and_upstream_temperature() -> None:
    for pa, pb in ((PS, 1.1e5), (2.0e5, 3.5e5)):
        forward = iso(pa, pb, 250.0, 400.0)
        assert iso(pb, pa, 400.0, 250.0) == -forward
        upstream_t = 250.0 if pa > pb else 400.0
        choked_or_not = iso6358_flux(max(pa, pb), min(pa, pb), upstream_t, B, LAMINAR)
        assert abs(forward) == pytest.approx(CONDUCTANCE * choked_or_not, rel=1e-12)
    assert iso(3e5, 3e5, 250.0, 400.0) == 0.0


def test_area_to_conductance_gives_the_same_choked_flow() -> None:
    c = area_to_sonic_conductance(AREA, C2)
    for tu in (280.0, 298.0, 320.0):
        assert iso(PS, 1e5, tu, c=c) == pytest.approx(flow(PS, 1e5, tu, area=AREA), rel=1e-12)
