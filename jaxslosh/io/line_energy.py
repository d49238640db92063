"""The energies of a lumped mooring line that a result file keeps (docs/reference/files.md):
`/energy/mooring/<line>/<part>`, J, computed by mooring/lumped.py (`energies`, `LineState`)."""

#: a lumped mooring line's energies, `/energy/mooring/<line>/<part>` (J; mooring/lumped.py `energies`)
LINE_ENERGY = {
    "kinetic": "the line's moving nodes' kinetic energy, their own mass",
    "added_kinetic": "the water's kinetic energy that the moving nodes' added mass carries",
    "elastic": "the segments' axial strain energy",
    "weight": "the moving nodes' submerged weight times their height (the frame of /mooring/<line>/nodes)",
    "seabed": "the seabed springs' energy",
    "dissipated": "the work the internal damping, the drag and the seabed's damping took out since the start",
    "fairlead_work": "the work the fairlead has done on the line since the start"}


def line_energy_of(d: dict, name: str):
    """{part: array} of line `name`'s energies in the datasets `d` (None where it has none: a
    catenary line, a file written before they were kept)."""
    if f"energy/mooring/{name}/kinetic" not in d:
        return None
    return {k: d[f"energy/mooring/{name}/{k}"] for k in LINE_ENERGY}
