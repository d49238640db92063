"""Writes the hydrodynamic databases of scenes/flng_side_by_side.toml: flng_side_by_side_flng.nc and
flng_side_by_side_carrier.nc, each hull alone as a box of its main dimensions (Capytaine 3, a lid on
the waterplane against the irregular frequencies, deep water), about its COG. Not run by the tests
(Capytaine is no dependency of jaxslosh). Run from the repository root with a Python that has
capytaine: python scenes/flng_side_by_side_hydro.py

Each body alone: the radiation and diffraction between the two hulls across the 5 m gap are left
out (a multibody file would couple them, docs/guide/bodies-and-connections.md; its undamped gap
resonance would need a damping lid calibrated on a model test, which a box model cannot give)."""
import os

import numpy as np
import xarray as xr
import capytaine as cpt

HERE = os.path.dirname(os.path.abspath(__file__))
RHO, G = 1025.0, 9.81
# 0.2 to 1.3 rad/s: the scene's sea (JONSWAP, Tp 10 s) takes its components in 0.3 to 1.2 rad/s;
# a 6 m panel is a seventh of the shortest wave (43 m at 1.2 rad/s)
OMEGA = np.linspace(0.2, 1.3, 12)
HEADINGS = np.radians([90.0, 135.0, 160.0, 180.0])
BOXES = {   # name: (length, beam, draft, KG above the keel, panel)
    "flng": (400.0, 65.0, 11.0, 25.0, 6.0),
    "carrier": (290.0, 46.0, 9.0, 18.5, 5.0),
}


def solve(name, L, B, T, kg, panel):
    res = tuple(max(2, int(np.ceil(s / panel))) for s in (L, B, 2 * T))
    mesh = cpt.mesh_parallelepiped(size=(L, B, 2 * T), center=(0.0, 0.0, 0.0), resolution=res, name=name)
    mesh = mesh.immersed_part()
    cog = (0.0, 0.0, kg - T)
    body = cpt.FloatingBody(mesh=mesh, lid_mesh=mesh.generate_lid(z=-0.05 * T), name=name,
                            dofs=cpt.rigid_body_dofs(rotation_center=cog), center_of_mass=cog, mass=RHO * L * B * T)
    solver = cpt.BEMSolver()
    coords = {"omega": OMEGA, "wave_direction": HEADINGS, "radiating_dof": list(body.dofs),
              "water_depth": [np.inf], "rho": [RHO], "g": [G]}
    ds = solver.fill_dataset(xr.Dataset(coords=coords), body)
    inf = solver.fill_dataset(xr.Dataset(coords={"omega": [np.inf], "radiating_dof": list(body.dofs),
                                                 "rho": [RHO], "g": [G]}), body)
    dofs = list(body.dofs)
    n = len(dofs)
    # the box's closed-form restoring about its COG (what the scene's [hydrostatics] hold): Capytaine's
    # own C_44 of this mesh came out 2 % lower, which the loader would flag against the scene's GM_T
    V, gm_t, gm_l = L * B * T, T / 2 + B ** 2 / (12 * T) - kg, T / 2 + L ** 2 / (12 * T) - kg
    C = np.diag([0.0, 0.0, RHO * G * L * B, RHO * G * V * gm_t, RHO * G * V * gm_l, 0.0])
    order = ("omega", "influenced_dof", "radiating_dof")
    A = np.concatenate([ds["added_mass"].transpose(*order).values, inf["added_mass"].transpose(*order).values])
    Bd = np.concatenate([ds["radiation_damping"].transpose(*order).values, np.zeros((1, n, n))])
    F = ds["excitation_force"].transpose("omega", "wave_direction", "influenced_dof").values
    F = np.concatenate([F, np.full((1,) + F.shape[1:], np.nan + 0j)])
    out = xr.Dataset({"added_mass": (order, A), "radiation_damping": (order, Bd),
                      "excitation_force": (("complex", "omega", "wave_direction", "influenced_dof"),
                                           np.stack([F.real, F.imag])),
                      "hydrostatic_stiffness": (("influenced_dof", "radiating_dof"), C)},
                     coords={"omega": np.append(OMEGA, np.inf), "influenced_dof": dofs, "radiating_dof": dofs,
                             "complex": ["re", "im"], "wave_direction": HEADINGS, "rho": RHO, "g": G,
                             "water_depth": np.inf, "space_coordinate": ["x", "y", "z"],
                             "center_of_mass": ("space_coordinate", np.asarray(cog)),
                             "rotation_center": ("space_coordinate", np.asarray(cog))},
                     attrs={"source": f"capytaine {cpt.__version__}, scenes/flng_side_by_side_hydro.py: "
                                      f"box {L:g} x {B:g} x {T:g} m, KG {kg:g} m, {mesh.nb_faces} panels"})
    path = os.path.join(HERE, f"flng_side_by_side_{name}.nc")
    out.to_netcdf(path, engine="h5netcdf")
    print(name, mesh.nb_faces, "panels;", os.path.getsize(path), "bytes; C33, C44, C55 =", C[2, 2], C[3, 3], C[4, 4])


if __name__ == "__main__":
    for name, spec in BOXES.items():
        solve(name, *spec)
