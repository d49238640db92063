"""Flexible structures tied by localized Lagrange multipliers (issue 4; paper eqs. 12-27): one mast
against the same mast in two parts. Its own file (the rest is in test_multibody.py) so that the two
xdist workers (`--dist loadfile`: a file per worker) can run the two files side by side: each
scene here costs tens of seconds of tracing and compilation, whatever its mesh."""
import numpy as np

import jaxslosh as js

from helpers import mast, multibody_vessel as vessel


def test_two_parts_tied_by_multipliers_move_as_one_body():
    """A mast meshed as one body, and the same mast as two parts (the upper tied to the lower by an
    interface frame and multipliers): forced sway of the vessel, no gravity. The lateral response
    (first order) agrees to 1e-8 relative; the floating frames differ only in the second-order
    terms (the tip's foreshortening, ~1e-7 of the sway here). With gravity each frame also carries
    its own share of the P-delta effect that linear elasticity lacks (1.4 % apart at W L^2/EI = 0.3)."""
    base = vessel(duration=0.5, dt=0.005, gravity=0.0, hydro=False,
                  extra_vessel='[vessel.forced]\ndof = "sway"\namplitude = 1e-6\nfrequency = 20.0\n')
    one = mast("mast", young=2.1e9) + '[[probes]]\nname = "tip"\nstructure = "mast"\npoint = [0.15, 0.15, 4.0]\n'
    two = mast("low", size=(0.3, 0.3, 2.0), mesh=(1, 1, 4), young=2.1e9) + \
        mast("high", origin=(-0.15, -0.15, 3.0), size=(0.3, 0.3, 2.0), mesh=(1, 1, 4), to="low", young=2.1e9) + \
        '[[probes]]\nname = "tip"\nstructure = "high"\npoint = [0.15, 0.15, 2.0]\n'
    r1, r2 = (js.simulate(js.load_scene(base + s)) for s in (one, two))
    assert r1.status == "ok" and r2.status == "ok"
    a, b = (np.asarray(r.probes["tip"].displacement) for r in (r1, r2))
    lateral = np.abs(a[:, 1]).max()
    assert lateral > 4e-6                              # the mast does respond (4.7e-6 m)
    diff = np.abs(a[:, 1] - b[:, 1]).max() / lateral
    print(f"lateral tip {lateral:.3e} m, relative difference {diff:.2e}; axial {np.abs(a[:, 2]).max():.2e} m")
    assert diff < 1e-8, diff
    assert np.abs(a[:, 2] - b[:, 2]).max() < 1e-6 * lateral   # second order
    assert np.max(r2.solver.constraint) < 1e-12
