"""The slip detectors on the taxels (fingers/tactile.py sliding_share, slip_warning, and the one that
needs no mu: shear_lag, shear_lag_warning, with edge_friction): their arithmetic on made-up fields,
their errors, and on a recorded load ramp: the v4 tissue warns of gross slip ahead of it and is
quiet while the grip holds with margin; the rigid twin's binned contacts are not (the mu detector
is on from the hold, the shear lag has no shear to read)."""

from __future__ import annotations

import numpy as np
import pytest

from softgrasp_env.accuracy import shear_under_load
from softgrasp_env.config import SimConfig
from softgrasp_env.fingers.tactile import (
    PRESSED_SHARE,
    SHEAR_LAG,
    SLIP_RATIO,
    SLIP_SHARE,
    TAXEL_CHANNELS,
    edge_friction,
    shear_lag,
    shear_lag_warning,
    sliding_share,
    slip_warning,
)
from softgrasp_env.presets import v4_tissue
from softgrasp_env.scene import GraspScene, SceneConfig


def _field(pressure, traction_y, traction_z=0.0):
    """(2, 2, 2, channels): pad 0 as given (each a (2, 2) array or a scalar), pad 1 empty."""
    f = np.zeros((2, 2, 2, len(TAXEL_CHANNELS)))
    f[0, ..., 0], f[0, ..., 1], f[0, ..., 2] = pressure, traction_y, traction_z
    return f


def test_the_sliding_share_is_the_pressure_on_taxels_at_the_cone():
    mu = 0.8
    p = np.array([[100.0, 300.0], [200.0, 400.0]])
    t = mu * p * np.array([[1.0, 0.5], [SLIP_RATIO + 1e-9, SLIP_RATIO - 1e-3]])  # taxels 0 and 2 at the cone or just past the ratio
    share = sliding_share(_field(p, t), mu)
    assert share.shape == (2,) and share[1] == 0.0  # the empty pad reads 0
    assert share[0] == pytest.approx((100.0 + 200.0) / 1000.0, rel=1e-12)
    # the traction's direction does not matter, only its size
    ty, tz = t * np.cos(0.7), t * np.sin(0.7)
    assert sliding_share(_field(p, ty, tz), mu)[0] == pytest.approx(0.3, rel=1e-12)
    # a batch of readings
    batch = np.stack([_field(p, t), _field(p, 0.0 * t)])
    assert np.allclose(sliding_share(batch, mu)[:, 0], [0.3, 0.0])
    assert list(slip_warning(batch, mu)) == [True, False]
    assert not slip_warning(_field(p, t), mu, share=0.31)


@pytest.mark.parametrize(("kwargs", "match"), [({"mu": 0.0}, "mu"), ({"mu": float("nan")}, "mu"),
                                               ({"mu": 0.5, "ratio": 1.5}, "ratio"),
                                               ({"mu": 0.5, "share": 0.0}, "share")])  # fmt: skip
def test_bad_detector_settings_are_errors(kwargs, match):
    with pytest.raises(ValueError, match=match):
        slip_warning(_field(1.0, 0.0), **kwargs)
    with pytest.raises(ValueError, match="taxels"):
        sliding_share(np.zeros((3, 2, 2, len(TAXEL_CHANNELS))), 0.5)


def _pad(pressure, shear_y, shear_z=0.0, traction_y=0.0, traction_z=0.0):
    """(2, 2, 2, channels): pad 0 as given (each a (2, 2) array or a scalar), pad 1 empty."""
    f = np.zeros((2, 2, 2, len(TAXEL_CHANNELS)))
    f[0, ..., 0], f[0, ..., 1], f[0, ..., 2], f[0, ..., 3], f[0, ..., 4] = (pressure, traction_y, traction_z,
                                                                          shear_y, shear_z)  # fmt: skip
    return f


def test_the_shear_lag_is_how_far_the_least_sheared_pressed_taxel_trails_the_most():
    p = np.array([[100.0, 100.0], [100.0, 100.0]])
    even = _pad(p, 1e-3)
    assert np.allclose(shear_lag(even), 0.0)  # the pad shears as one layer
    edge = _pad(p, np.array([[1e-3, 1e-3], [1e-3, 0.4e-3]]))
    lag = shear_lag(edge)
    assert lag.shape == (2,) and lag[1] == 0.0  # the empty pad: no signal
    assert lag[0] == pytest.approx(0.6, rel=1e-12)
    # the direction of the shear does not matter, only the spread along it
    turned = _pad(p, np.array([[1e-3, 1e-3], [1e-3, 0.4e-3]]) * np.cos(2.0),
                  np.array([[1e-3, 1e-3], [1e-3, 0.4e-3]]) * np.sin(2.0))  # fmt: skip
    assert shear_lag(turned)[0] == pytest.approx(0.6, rel=1e-9)
    # a taxel pressed below PRESSED_SHARE of the pad's most is not part of the contact
    light = _pad(np.array([[100.0, 100.0], [100.0, 0.5 * PRESSED_SHARE * 100.0]]), np.array([[1e-3, 1e-3], [1e-3, 0.0]]))
    assert shear_lag(light)[0] == 0.0
    assert shear_lag(light, pressed=0.0)[0] == pytest.approx(1.0)
    # a pressed taxel sheared backward against the rest is clipped to 1; no shear at all (rigid pads) is 0
    assert shear_lag(_pad(p, np.array([[1e-3, 1e-3], [1e-3, -1e-3]])))[0] == 1.0
    assert shear_lag(_pad(p, 0.0))[0] == 0.0
    # a batch; the warning on either pad
    batch = np.stack([even, edge])
    assert np.allclose(shear_lag(batch)[:, 0], [0.0, 0.6])
    assert list(shear_lag_warning(batch)) == [False, True]
    assert not shear_lag_warning(edge, lag=0.61)


def test_the_edge_friction_reads_the_ratio_along_the_pads_traction():
    """The in-face parts of the normal force on the flanks of a curved contact cancel over the pad:
    they are not friction."""
    p = np.array([[100.0, 100.0], [50.0, 50.0]])
    tz = np.array([[30.0, 30.0], [40.0, 40.0]])  # the load along z; the lower taxels at 0.8
    ty = np.array([[-20.0, 20.0], [-30.0, 30.0]])  # the flanks' normals, opposite across the strip
    mu = edge_friction(_pad(p, 0.0, traction_y=ty, traction_z=tz))
    assert mu.shape == (2,) and mu[1] == 0.0
    assert mu[0] == pytest.approx(0.8, rel=1e-12)  # |t| / p would read 1.0 there
    assert edge_friction(_pad(p, 0.0, traction_z=-tz))[0] == pytest.approx(0.8, rel=1e-12)  # the sign does not matter


@pytest.mark.parametrize(("call", "match"), [
    (lambda f: shear_lag(f, pressed=1.5), "pressed"),
    (lambda f: shear_lag(f, pressed=float("nan")), "pressed"),
    (lambda f: shear_lag_warning(f, lag=0.0), "lag"),
    (lambda f: shear_lag_warning(f, lag=1.2), "lag"),
    (lambda f: edge_friction(f, pressed=-0.1), "pressed"),
    (lambda f: shear_lag(f[0]), "taxels must be"),
    (lambda f: shear_lag(f[..., :4]), "taxels must be"),
    (lambda f: edge_friction(np.where(f == 0.0, np.nan, f)), "finite"),
    (lambda f: shear_lag_warning(np.full_like(f, np.inf)), "finite"),
])  # fmt: skip
def test_bad_input_to_the_mu_free_detector_is_named(call, match):
    with pytest.raises(ValueError, match=match):
        call(_pad(100.0, 1e-3))


def _ramp(cfg: SceneConfig):
    scene = GraspScene(cfg)
    try:
        rec = shear_under_load(scene, rate=2.0, every=2, rows=4, cols=4)
        mu = scene.config.tissue.friction_static
    finally:
        scene.close()
    return rec, mu


@pytest.fixture(scope="module", params=["groups", "global"])
def tissue_ramp(request):
    """The v4 tissue's ramp, its material swept group by group (the soft ids' v4) and solved
    globally (their v5)."""
    return _ramp(SceneConfig(tissue=v4_tissue(), sim=SimConfig(material_solve=request.param)))


@pytest.fixture(scope="module")
def rigid_ramp():
    return _ramp(SceneConfig(fingers="rigid"))


def _lead(rec, warn) -> float:
    """The share of the slip load between the start of the warning's last run and gross slip."""
    assert warn[-1]
    start = len(warn) - 1
    while start > 0 and warn[start - 1]:
        start -= 1
    return float((rec.slip_load - rec.load[start]) / rec.slip_load)


def test_the_tissue_warns_of_gross_slip_ahead_of_it_and_not_while_it_holds_with_margin(tissue_ramp):
    """The default cylinder, 3 N per finger, mu 0.9, its weight grown at 2 N/s until it slides
    1 mm in the grip. Measured: slip at 4.82 N, the warning from 3.57 N on without a break (26 % of
    the slip load, 0.63 s ahead), off throughout below half the slip load (the band of rates,
    squeezes and frictions: benchmarks/slip_warning.py); solved globally, slip at 4.86 N, warned
    from 3.66 N (25 %, 0.60 s)."""
    rec, mu = tissue_ramp
    warn = slip_warning(rec.fields, mu)
    assert np.isfinite(rec.slip_load)
    assert not warn[rec.load < 0.5 * rec.slip_load].any()
    lead = _lead(rec, warn)
    assert 0.2 <= lead < 0.5, lead  # the target: 20 % of the load ahead


def test_the_tissue_feels_slip_coming_without_knowing_mu(tissue_ramp):
    """The same ramp through the shear lag, which is not told mu. Measured: the lag at most 0.18
    below half the slip load, the warning (lag >= 0.25) from 3.34 N of a 4.82 N slip load on
    without a break (31 % of the load ahead); the band: 26-41 %, never on below half the slip load
    (benchmarks/slip_warning.py); solved globally, 30 % ahead (25-41 % over the band). The sliding
    edges then read mu: edge_friction 1.01-1.06 x mu over the last tenth of the ramp."""
    rec, mu = tissue_ramp
    lag = shear_lag(rec.fields).max(axis=-1)
    assert lag[rec.load < 0.5 * rec.slip_load].max() < SHEAR_LAG
    warn = shear_lag_warning(rec.fields)
    assert not warn[rec.load < 0.5 * rec.slip_load].any()
    lead = _lead(rec, warn)
    assert 0.2 <= lead < 0.5, lead  # ahead of gross slip; the time it gives is the benchmark's
    near = rec.load > 0.9 * rec.slip_load
    read = edge_friction(rec.fields[near]).max(axis=-1) / mu
    assert np.all((read > 0.9) & (read < 1.2)), read


def test_the_rigid_twins_contacts_read_as_sliding_from_the_hold(rigid_ramp):
    """pybullet's contact points on the bare rigid pads: one of them sits at its friction cone
    from the hold on, so the mu detector is on far from slip and warns of nothing (measured on at
    1.2 N of a 5.6 N slip load); the rigid pads do not shear, so the shear lag reads nothing."""
    rec, mu = rigid_ramp
    assert slip_warning(rec.fields, mu)[rec.load < 0.5 * rec.slip_load].any()
    assert not shear_lag_warning(rec.fields).any() and not shear_lag(rec.fields).any()
    assert SLIP_SHARE == 0.1 and SLIP_RATIO == 0.9 and SHEAR_LAG == 0.25  # the settings these measurements are of
