"""The elastic catenary of one line (jaxslosh/mooring/catenary.py) against MoorPy's and MAP++'s
published numbers, an independent quadrature of the line's shape, and finite differences."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxslosh.mooring.catenary import catenary

# MoorPy's own reference cases: NREL/MoorPy, tests/test_catenary.py (inputs and MoorPy's answers
# copied as data). Inputs: XF, ZF, L, EA, w, CB (CB >= 0: seabed friction; CB < 0: the anchor -CB
# above the seabed). Answers: fAH, fAV (force on the anchor), fBH, fBV (force on the fairlead,
# negative towards the anchor and downwards), LBot.
MOORPY_IN = [
    [400, 200, 500.0, 7510000000000.0, 800.0, 5.0],
    [400, 200, 500.0, 7510000000000.0, 800.0, 0.0],
    [400, 200, 500.0, 7510000000000.0, 800.0, 0.1],
    [400, 200, 500.0, 7510000000000.0, 200.0, -372.7],
    [89.9, 59.2, 130.0, 751000000.0, 881.05, -372.7],
    [37.96888656874307, 20.49078283711694, 100.0, 751000000.0, -881.0549577007893, -1245.2679469540894],
    [246.22420940032947, 263.55766330843164, 360.63566262396927 - 0.01, 700e6, 3.08735, 0],
    [246.22420940032947, 263.55766330843164, 360.63566262396927, 700e6, 3.08735, 0],
    [246.22420940032947, 263.55766330843164, 360.63566262396927 + 0.01, 700e6, 3.08735, 0],
    [119.3237383002058, 52.49668849178113, 130.36140355177318, 700000000.0, 34.91060469991227, 0],
]
MOORPY_OUT = [
    [0.0, 0.0, -96643.43501616362, -237751.75997440016, 202.81030003199982],
    [96643.42815934008, 0.0, -96643.42815934008, -237751.75535996316, 202.81030580004602],
    [80418.60434855078, 0.0, -96643.42877136687, -237751.75577183915, 202.81030528520108],
    [43694.580989249596, -22365.599350216216, -43694.580989249596, -77634.40064978378, 0],
    [31373.229006023103, -26650.341270116318, -31373.229006023103, -87886.15872988368, 0],
    [6428.437434537766, 53178.729367882406, -6428.437434537766, 34926.76640219652, 0],
    [71116.8, 75567.3, -71116.8, -76680.6, 0],
    [56804.6, 60803.4, -56804.6, -60803.4, 0],
    [46077.1, 48765.2, -46077.1, -49878.6, 0],
    [72694.145, 29715.173, -72694.145, -34266.168, 0],
]
# MoorPy's case 7 (the "hardest" near-taut line) is its own approximation, not the catenary: its
# fairlead and anchor vertical forces are equal, though the line weighs w L = 1113 N between them
# (cases 6 and 8, 1 cm shorter and longer, carry it). Checked below against a quadrature instead.
MOORPY_APPROXIMATE = 7


def _ours(case):
    XF, ZF, L, EA, w, CB = case
    c = catenary((XF, ZF), L, w, EA, seabed_friction=max(CB, 0.0), anchor_height=max(-CB, 0.0))
    return c, np.array([c.anchor_horizontal, c.anchor_vertical, -c.fairlead_horizontal,
                        -c.fairlead_vertical, c.seabed_length])


@pytest.mark.parametrize("index", [i for i in range(len(MOORPY_IN)) if i != MOORPY_APPROXIMATE])
def test_moorpy_cases(index):
    _, got = _ours(MOORPY_IN[index])
    want = np.array(MOORPY_OUT[index])
    # MoorPy's zeros are exact (no anchor force under full friction, no seabed length): compared
    # with an absolute tolerance of 1e-5 of the line's tension
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-5 * np.max(np.abs(want)))


def _quadrature_spans(H, V, L, w, EA, n=200001):
    """(XF, ZF) of a fully suspended line with fairlead tension (H, V), by integrating its
    stretched tangent along the unstretched arc length (trapezoids): independent of the closed form."""
    s = np.linspace(0.0, L, n)
    Vs = V - w * (L - s)                  # vertical tension at s from the anchor
    T = np.hypot(H, Vs)
    dx = H / T * (1 + T / EA)
    dz = Vs / T * (1 + T / EA)
    return np.trapezoid(dx, s), np.trapezoid(dz, s)


def test_moorpy_near_taut_case_by_quadrature():
    XF, ZF, L, EA, w, _ = MOORPY_IN[MOORPY_APPROXIMATE]
    c, got = _ours(MOORPY_IN[MOORPY_APPROXIMATE])
    xq, zq = _quadrature_spans(float(c.fairlead_horizontal), float(c.fairlead_vertical), L, w, EA)
    np.testing.assert_allclose([xq, zq], [XF, ZF], rtol=1e-9)
    # the line carries its weight, and the answer lies between its 1-cm neighbours'
    assert got[1] + got[3] == pytest.approx(-w * L, rel=1e-9)
    assert MOORPY_OUT[MOORPY_APPROXIMATE + 1][0] < got[0] < MOORPY_OUT[MOORPY_APPROXIMATE - 1][0]


def test_moorpy_symmetric_u():
    """MoorPy's U-shaped line (anchor 20 m above the seabed, fairlead at its height) equals half of
    it solved as a line anchored on the seabed (NREL/MoorPy tests/test_catenary.py)."""
    half = catenary((50.0, 20.0), 65.0, 100.0, 1e12)
    u = catenary((100.0, 0.0), 130.0, 100.0, 1e12, anchor_height=20.0)
    np.testing.assert_allclose([u.anchor_horizontal, u.anchor_vertical, u.fairlead_horizontal, u.fairlead_vertical],
                               [half.fairlead_horizontal, -half.fairlead_vertical, half.fairlead_horizontal,
                                half.fairlead_vertical], rtol=1e-10)
    assert float(u.seabed_length) == pytest.approx(2 * float(half.seabed_length), rel=1e-10)


def test_oc3_hywind_line_equals_map():
    """OC3-Hywind's line at rest (MAP++'s published solution): H = 736,939 N, V = 535,728 N, 134.785 m
    on the seabed."""
    c = catenary((853.87 - 5.2, 320.0 - 70.0), 902.2, 698.094, 384.243e6)
    np.testing.assert_allclose([c.fairlead_horizontal, c.fairlead_vertical, c.seabed_length],
                               [736939.0, 535728.0, 134.785], rtol=1e-5)
    assert float(c.anchor_horizontal) == float(c.fairlead_horizontal)   # frictionless seabed
    assert float(c.anchor_vertical) == 0.0


def test_buoyant_line_is_the_mirror_of_a_hanging_one():
    hang = catenary((40.0, -20.0), 100.0, 881.0, 7.5e8, anchor_height=1e3)
    buoy = catenary((40.0, 20.0), 100.0, -881.0, 7.5e8, anchor_height=1e3)
    np.testing.assert_allclose([buoy.fairlead_horizontal, buoy.fairlead_vertical],
                               [hang.fairlead_horizontal, -hang.fairlead_vertical], rtol=1e-10)


def test_weightless_taut_line_is_a_spring():
    c = catenary((30.0, 40.0), 49.0, 0.0, 1e6)
    T = 1e6 * (50.0 / 49.0 - 1.0)
    np.testing.assert_allclose([c.fairlead_horizontal, c.fairlead_vertical], [0.6 * T, 0.8 * T], rtol=1e-10)


def test_continuous_across_the_branches():
    """H(XF) through slack (piled on the seabed) -> touchdown -> suspended -> taut, for an anchor
    on the seabed and a raised one (U-shaped -> lifted off): no jump where the branch changes
    (a jump would be far larger than the steps on either side)."""
    L, w, EA = 300.0, 500.0, 1e9
    for hA, ZF in ((0.0, 100.0), (10.0, 90.0)):
        xs = jnp.linspace(150.0, 290.0, 141)
        c = jax.vmap(lambda x: catenary((x, ZF), L, w, EA, anchor_height=hA))(xs)
        H, LB = np.array(c.fairlead_horizontal), np.array(c.seabed_length)
        branch = np.where(H < 1e-6, 0, np.where(LB > 0, 1, 2))
        assert set(branch) == {0, 1, 2}
        jumps = np.abs(np.diff(H))
        for i in np.flatnonzero(np.diff(branch)):
            assert jumps[i] <= 3 * max(jumps[i - 1], jumps[i + 1]) + 1e-9 * H[i + 1], (hA, i)


def test_slack_line_piles_on_the_seabed():
    c = catenary((100.0, 100.0), 300.0, 500.0, 1e9)
    assert float(c.fairlead_horizontal) < 1e-9
    assert float(c.fairlead_vertical) == pytest.approx(500.0 * 100.0, rel=1e-4)
    assert float(c.seabed_length) == pytest.approx(200.0, rel=1e-4)


CASES = [  # (XF, ZF, L, w, EA, CB, hA): each branch
    (848.67, 250.0, 902.2, 698.094, 384.243e6, 0.0, 0.0),      # touchdown, frictionless
    (400.0, 200.0, 500.0, 800.0, 7.5e9, 0.1, 0.0),             # touchdown with friction
    (400.0, 200.0, 500.0, 200.0, 7.5e9, 0.0, 372.7),           # suspended, raised anchor
    (100.0, 0.0, 130.0, 100.0, 1e9, 0.0, 20.0),                # U-shaped
    (37.97, 20.49, 100.0, -881.05, 7.51e8, 0.0, 1245.0),       # buoyant
    (246.22, 263.56, 360.5, 3.08735, 700e6, 0.0, 0.0),          # near taut
]


@pytest.mark.parametrize("case", CASES)
def test_gradients_in_every_argument(case):
    args = np.array(case, dtype=float)

    def outputs(a):
        c = catenary((a[0], a[1]), a[2], a[3], a[4], a[5], a[6])
        return jnp.stack([c.fairlead_horizontal, c.fairlead_vertical, c.anchor_horizontal,
                          c.anchor_vertical, c.seabed_length, c.stiffness[0, 0], c.stiffness[1, 1]])

    J = np.array(jax.jacfwd(outputs)(jnp.asarray(args)))
    Jr = np.array(jax.jacrev(outputs)(jnp.asarray(args)))
    np.testing.assert_allclose(Jr, J, rtol=1e-8, atol=1e-8 * np.max(np.abs(J)))
    for k in range(7):
        if k >= 5 and args[k] == 0.0:
            continue      # friction or anchor height at its bound: one-sided only
        h = 1e-6 * max(abs(args[k]), 1.0)
        e = np.zeros(7)
        e[k] = h
        fd = (np.array(outputs(jnp.asarray(args + e))) - np.array(outputs(jnp.asarray(args - e)))) / (2 * h)
        scale = np.abs(np.array(outputs(jnp.asarray(args)))) / max(abs(args[k]), 1.0) + 1e-3
        np.testing.assert_allclose(J[:, k], fd, rtol=1e-4, atol=1e-5 * float(np.max(scale)),
                                   err_msg=f"argument {k}")


def test_stiffness_is_the_inverse_of_the_profile_jacobian():
    from jaxslosh.mooring.catenary import profile
    XF, ZF, L, w, EA = 848.67, 250.0, 902.2, 698.094, 384.243e6
    c = catenary((XF, ZF), L, w, EA)
    J = jax.jacfwd(lambda x: jnp.stack(profile(x[0], x[1], L, w, EA)[:2]))(
        jnp.stack([c.fairlead_horizontal, c.fairlead_vertical]))
    np.testing.assert_allclose(np.array(c.stiffness) @ np.array(J), np.eye(2), atol=1e-10)
