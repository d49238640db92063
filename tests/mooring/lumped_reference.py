"""An independent reference for the lumped-mass line's tests: the elastic catenary with a
frictionless seabed run (Jonkman's equations for the fairlead tension's components H, V), solved
with scipy's fsolve in NumPy (no JAX, nothing shared with jaxslosh/mooring)."""
import numpy as np
from scipy.optimize import fsolve

# the OC3-Hywind line (OpenFAST's r-test, MAP++): depth 320 m, anchor radius 853.87 m, fairlead
# radius 5.2 m at 70 m below the water; the published solution H, V (N) and seabed length (m)
OC3 = dict(depth=320.0, anchor=(-853.87, 0.0, -320.0), fairlead=(-5.2, 0.0, -70.0), length=902.2,
           weight=698.094, ea=384.243e6, diameter=0.09, mass=77.7066)
OC3_HV = (736939.0, 535728.0, 134.785)


def profile(H, V, L, w, EA):
    """(XF, ZF) of the line whose fairlead tension is (H, V): with a seabed run when V < w L."""
    if V < w * L:
        xf = L - V / w + H / w * np.arcsinh(V / H) + H * L / EA
        zf = H / w * (np.sqrt(1.0 + (V / H) ** 2) - 1.0) + V * V / (2.0 * EA * w)
    else:
        a, b = V / H, (V - w * L) / H
        xf = H / w * (np.arcsinh(a) - np.arcsinh(b)) + H * L / EA
        zf = H / w * (np.sqrt(1.0 + a * a) - np.sqrt(1.0 + b * b)) + (V * L - 0.5 * w * L * L) / EA
    return xf, zf


def catenary(XF, ZF, L, w, EA, start=(7e5, 5e5)):
    """(H, V, seabed length) for the spans XF, ZF."""
    def eqs(x):
        H, V = x
        xf, zf = profile(H, V, L, w, EA)
        return [(xf - XF) / L, (zf - ZF) / L]
    (H, V), info, ok, msg = fsolve(eqs, start, xtol=1e-13, full_output=True)
    assert np.max(np.abs(eqs((H, V)))) < 1e-12, msg
    return H, V, max(L - V / w, 0.0)


def oc3_catenary(dx=0.0):
    """The OC3 line's (H, V, seabed length) with the fairlead moved dx m towards the anchor's far side."""
    c = OC3
    XF = c["fairlead"][0] + dx - c["anchor"][0]
    ZF = c["fairlead"][2] - c["anchor"][2]
    return catenary(XF, ZF, c["length"], c["weight"], c["ea"])
