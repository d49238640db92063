"""Regenerates the small Capytaine datasets of tests/bodies (not run by the tests: Capytaine is
no dependency of jaxslosh or its tests). Run with a Python that has capytaine (3.x):

    python tests/data/bodies/generate.py

Two boxes, coarse meshes, a few frequencies below their first irregular frequencies (about
2.3 rad/s): a barge (20 x 8 m, draft 2.5 m) at the origin and a tender (12 x 6 m, draft 2 m) beside
it at y = 14 m (a 7 m gap), solved together (`two_boxes.nc`, with Capytaine's own `post_pro.rao`
in `two_boxes_rao.npz`) and each alone about its own COG (`barge.nc`, `tender.nc`). Every body
rotates about its own COG; the wave phases are relative to the barge's COG (x = y = 0)."""
import os

import numpy as np
import xarray as xr
import capytaine as cpt

HERE = os.path.dirname(os.path.abspath(__file__))
RHO, G = 1025.0, 9.81
OMEGA = np.linspace(0.3, 2.0, 12)
HEADINGS = [0.0, np.pi / 2]
BOXES = {   # name: (L, B, draft, kg, (x, y) of the COG)
    "barge": (20.0, 8.0, 2.5, 2.0, (0.0, 0.0)),
    "tender": (12.0, 6.0, 2.0, 1.5, (0.0, 14.0)),
}


def box(name, L, B, T, kg, xy, panel=0.6):
    zg = kg - T
    res = tuple(max(2, int(np.ceil(s / panel))) for s in (L, B, 2 * T))
    mesh = cpt.mesh_parallelepiped(size=(L, B, 2 * T), center=(xy[0], xy[1], 0.0), resolution=res, name=name)
    mesh = mesh.immersed_part()
    cog = (xy[0], xy[1], zg)
    body = cpt.FloatingBody(mesh=mesh, dofs=cpt.rigid_body_dofs(rotation_center=cog), center_of_mass=cog,
                            mass=RHO * L * B * T, name=name)
    m = RHO * L * B * T
    I = np.diag([m, m, m, m * (0.35 * B) ** 2, m * (0.25 * L) ** 2, m * (0.26 * L) ** 2])
    return body, I


def solve(bodies, inertias, stem):
    body = bodies[0] if len(bodies) == 1 else cpt.Multibody(bodies, name="two_boxes")
    solver = cpt.BEMSolver()
    test = __import__("xarray").Dataset(coords={"omega": OMEGA, "wave_direction": HEADINGS,
                                                "radiating_dof": list(body.dofs), "water_depth": [np.inf],
                                                "rho": [RHO], "g": [G]})
    ds = solver.fill_dataset(test, body)
    inf = solver.fill_dataset(__import__("xarray").Dataset(coords={"omega": [np.inf], "radiating_dof": list(body.dofs),
                                                                   "rho": [RHO], "g": [G]}), body)
    n = len(body.dofs)
    M = np.zeros((n, n))
    C = np.zeros((n, n))
    for k, (b, I) in enumerate(zip(bodies, inertias)):
        M[6 * k:6 * k + 6, 6 * k:6 * k + 6] = I
        Ck = np.asarray(b.compute_hydrostatic_stiffness(rho=RHO, g=G))
        C[6 * k:6 * k + 6, 6 * k:6 * k + 6] = Ck
    dofs = list(body.dofs)
    ds["inertia_matrix"] = (("influenced_dof", "radiating_dof"), M)
    ds["hydrostatic_stiffness"] = (("influenced_dof", "radiating_dof"), C)
    rao = cpt.post_pro.rao(ds)
    np.savez(os.path.join(HERE, f"{stem}_rao.npz"), omega=OMEGA, headings=np.asarray(HEADINGS), dofs=np.asarray(dofs),
             rao=rao.transpose("omega", "wave_direction", "radiating_dof").values,
             added_mass_infinite=inf["added_mass"].values.squeeze(), inertia=M, stiffness=C)
    # Capytaine's layout (complex values split along `complex`, A_inf as an omega = inf row), the
    # dataset's numbers as solved
    w = np.append(OMEGA, np.inf)
    order = ("omega", "influenced_dof", "radiating_dof")
    A = np.concatenate([ds["added_mass"].transpose(*order).values, inf["added_mass"].transpose(*order).values])
    B = np.concatenate([ds["radiation_damping"].transpose(*order).values, np.zeros((1, n, n))])
    F = ds["excitation_force"].transpose("omega", "wave_direction", "influenced_dof").values
    F = np.concatenate([F, np.full((1,) + F.shape[1:], np.nan + 0j)])
    out = xr.Dataset({"added_mass": (order, A), "radiation_damping": (order, B),
                      "excitation_force": (("complex", "omega", "wave_direction", "influenced_dof"),
                                           np.stack([F.real, F.imag])),
                      "hydrostatic_stiffness": (("influenced_dof", "radiating_dof"), C)},
                     coords={"omega": w, "influenced_dof": dofs, "radiating_dof": dofs, "complex": ["re", "im"],
                             "wave_direction": np.asarray(HEADINGS), "rho": RHO, "g": G, "water_depth": np.inf},
                     attrs={"source": f"capytaine {cpt.__version__}, tests/data/bodies/generate.py"})
    if len(bodies) == 1:
        out = out.assign_coords(center_of_mass=("space_coordinate", np.asarray(bodies[0].center_of_mass)),
                                rotation_center=("space_coordinate", np.asarray(bodies[0].center_of_mass)),
                                space_coordinate=["x", "y", "z"])
    out.to_netcdf(os.path.join(HERE, f"{stem}.nc"), engine="h5netcdf")
    print(dofs)
    print(stem, os.path.getsize(os.path.join(HERE, f"{stem}.nc")), "bytes")


made = {name: box(name, *spec) for name, spec in BOXES.items()}
solve([made["barge"][0], made["tender"][0]], [made["barge"][1], made["tender"][1]], "two_boxes")
for name in BOXES:
    solve([made[name][0]], [made[name][1]], name)
