"""What every scene key means: its default, unit and meaning, for the scene reference of the
documentation (docs/hooks.py writes the page from these rows; tests/docs/test_docs.py holds them to the
keys the loader accepts).

A key is written as the scene file writes it, without indices: `tanks.fluid.density` is the
`density` of a `[tanks.fluid]` table under any `[[tanks]]`. `<channel>` stands for a channel name
(`roll`, `pitch`, `heave`, `probe.<name>`, `mooring.<line>`). Data only: nothing here is read by the loader.
"""
from __future__ import annotations

#: the tables, in the order the reference lists them: (table, what it holds)
TABLES = (
    ("", "The top level of the scene file."),
    ("environment", "The world around the vessel."),
    ("simulation", "The time integration and the Newton solver of each step."),
    ("vessel", "The rigid hull; its frame origin is its centre of gravity (COG), body axes x forward, "
               "y to port, z up."),
    ("vessel.hydrostatics", "Linear restoring about the initial equilibrium (paper eqs. 33-38)."),
    ("vessel.initial", "The initial state; every key optional, zero by default."),
    ("vessel.forced", "A prescribed motion of one rigid dof, or of any of them from a record (tank tests); "
                      "the others are held."),
    ("vessel.hull", "The hull's geometry: Froude-Krylov forces, Capytaine, closed-form box hydrostatics."),
    ("vessel.hydrodynamics", "Radiation (added mass, damping, memory) and excitation tables, a database "
                             "file, or Capytaine."),
    ("tanks", "Zero or more `[[tanks]]` of liquid carried by the vessel."),
    ("tanks.fluid", "The tank's liquid."),
    ("tanks.walls", "Elastic tank walls (the table alone makes the walls elastic)."),
    ("tanks.walls.material", "The walls' linear elastic material."),
    ("tanks.reduction", "The liquid on its lowest natural modes (a cheaper accuracy level); every tank "
                        "or none."),
    ("tanks.damping", "Damping of the tank's sloshing modes (none when absent)."),
    ("tanks.baffles", "Zero or more `[[tanks.baffles]]`: thin rigid plates across a box or prismatic tank."),
    ("tanks.chamfers", "Prismatic tanks' corner cuts written as a table (or as a list: `[[w, h], [w, h]]`)."),
    ("structures", "Zero or more `[[structures]]`: flexible blocks of linear elastic hexahedra."),
    ("structures.material", "The structure's linear elastic material."),
    ("probes", "Zero or more `[[probes]]`: material points recorded in the result."),
    ("effects", "Switches to leave an effect out (to measure what it contributes); all on by default."),
    ("waves", "Incident linear (Airy) waves."),
    ("mooring", "Zero or more `[[mooring]]` lines from the seabed to the vessel or a body (guide: Moorings)."),
    ("bodies", "Zero or more `[[bodies]]`: rigid floating bodies beside the vessel, each in its own frame "
               "(guide: Bodies and connections)."),
    ("bodies.hydrostatics", "The body's restoring, as `[vessel.hydrostatics]`: linear about its rest pose, or "
                            "nonlinear on its hull."),
    ("bodies.hull", "The body's hull, with `[vessel.hull]`'s keys, in its frame from its COG: its nonlinear "
                    "hydrostatics, a box's closed forms, its connection points' bounds."),
    ("bodies.hydrodynamics", "The body's hydrodynamics, with `[vessel.hydrodynamics]`'s keys (tables, a file, "
                             "viscous damping; not `capytaine`): about its COG, in its axes; "
                             "a multibody file couples the bodies it names."),
    ("bodies.initial", "The body's initial state, as `[vessel.initial]`; every key optional, zero by default."),
    ("connections", "Zero or more `[[connections]]`: hawsers, fenders and springs between two bodies, or a "
                    "body and a fixed point (guide: Bodies and connections)."),
    ("campaign", "A campaign's defaults (`jaxslosh campaign`, `js.campaign`); `jaxslosh run` ignores it."),
    ("campaign.limits", "Operability limits per channel."),
)

_REQ = "required"

#: (key, default, unit, meaning)
KEYS = (
    ("title", "the file's stem", "", "The scene's title (figures and summaries)."),
    # environment
    ("environment.gravity", "9.81", "m/s^2", "Gravity along -Z; 0 for a body without gravity."),
    ("environment.water_density", "1025.0", "kg/m^3", "The sea water that gives buoyancy."),
    ("environment.depth", "infinite", "m", "Water depth: the seabed of mooring lines (required with `[[mooring]]`)."),
    # simulation
    ("simulation.duration", _REQ, "s", "Simulated time."),
    ("simulation.dt", _REQ, "s", "The fixed time step."),
    ("simulation.scheme", '"hht"', "", '"newmark" (trapezoidal rule), "hht" or "generalized-alpha".'),
    ("simulation.alpha", "0.0", "", "HHT: gamma = 1/2 + alpha, beta = (1 + alpha)^2 / 4, 0 <= alpha <= 1/3."),
    ("simulation.rho_inf", "1.0", "", "Generalized-alpha: the spectral radius at infinite frequency."),
    ("simulation.save_every", "1", "steps", "Keep every n-th step in the result."),
    ("simulation.tolerance", "1e-10", "m/s^2, rad/s^2",
     "Newton converges when the residual over the mass (an acceleration error) is below this."),
    ("simulation.max_iterations", "25", "", "Newton iterations per step before the step counts as failed "
                                            "(exit status 3)."),
    ("simulation.chunk", "0 (automatic)", "frames", "Saved frames per compiled chunk (the result file grows "
                                                   "chunk by chunk)."),
    ("simulation.substeps", "0", "", "When > 1, a step whose Newton iteration fails is retried as this many "
                                     "sub-steps."),
    ("simulation.linear_solver", '"auto"', "", 'The liquid block of the Newton matrix: "dense" inverses, '
     '"sparse" (fast diagonalization on box grids, else factors computed at build time and applied in JAX), '
     '"sparse-host" (SciPy SuperLU called from the step: very large shaped meshes; no export, batching or '
     'cache), "auto": sparse above 1,500 liquid unknowns. Face-normal ("rt") tanks at full order: every '
     'value but "dense" takes their blocks without dense matrices on the faces (docs/guide/linear-solvers.md).'),
    ("simulation.energy_projection", "false", "", 'scheme = "newmark" in a conservative scene only: after each '
     "step the velocities are scaled back onto the initial energy."),
    # vessel
    ("vessel.name", '"vessel"', "", "How mooring lines (`mooring.body`), connections (`connections.bodies`) and "
                                    "tanks (`tanks.body`) name the vessel (\"vessel\" names it too)."),
    ("vessel.cog_height", "box hull: kg - draft; else 0", "m", "The COG's height above the still-water level at "
                                                                "rest (it places the mooring fairleads)."),
    ("vessel.footprint", "the circle of the waterplane area", "m", "[length, beam] of the waterplane at rest: "
     "the overlap check of `[[bodies]]` compares this rectangle (ships side by side) instead of the circle; "
     "the connection points must lie within it."),
    ("vessel.mass", _REQ, "kg", "The whole ship without its tank liquid (structures and elastic walls "
                                "included)."),
    ("vessel.inertia", _REQ, "kg m^2", "About the COG in body axes: 3 diagonal values or a 3 x 3 list "
                                       "(symmetric, positive definite)."),
    ("vessel.hydrostatics.waterplane_area", _REQ, "m^2", "A_w."),
    ("vessel.hydrostatics.displaced_volume", _REQ, "m^3", "The displaced volume V."),
    ("vessel.hydrostatics.gm_t", _REQ, "m", "Transverse metacentric height, tank liquid frozen (<= 0 runs, "
                                            "with a warning)."),
    ("vessel.hydrostatics.gm_l", _REQ, "m", "Longitudinal metacentric height."),
    ("vessel.hydrostatics.model", '"linear"', "", '"linear": GM springs (eqs. 33-38); "nonlinear": the still-'
     "water pressure on the hull's instantaneous wetted surface and the weight; with [waves] the incident-wave "
     "pressure on that surface too."),
    ("vessel.hydrostatics.moment", '"conservative"', "", '"conservative": the gradient of a restoring '
     'potential, equal to eq. (36) for pure roll or pitch; "paper": eq. (36) literally.'),
    ("vessel.initial.position", "[0, 0, 0]", "m", "Inertial offset of the COG from its equilibrium."),
    ("vessel.initial.velocity", "[0, 0, 0]", "m/s", "Inertial velocity of the COG."),
    ("vessel.initial.angular_velocity", "[0, 0, 0]", "rad/s", "Body frame."),
    ("vessel.initial.roll_pitch_yaw", "[0, 0, 0]", "rad", "Initial attitude (yaw, then pitch, then roll)."),
    ("vessel.forced.dof", "required (harmonic, spin-up)", "",
     '"surge", "sway", "heave", "roll", "pitch" or "yaw".'),
    ("vessel.forced.profile", '"harmonic" ("record" with file)', "", '"harmonic": amplitude sin(frequency t + '
     'phase), faded in over ramp; "spin-up": a rotation whose rate grows smoothly to rate over duration, then '
     'stays; "record": the motion of file.'),
    ("vessel.forced.amplitude", "required (harmonic)", "m or rad", "Harmonic amplitude."),
    ("vessel.forced.frequency", "required (harmonic)", "rad/s", "Harmonic frequency."),
    ("vessel.forced.phase", "0", "rad", "Harmonic phase: x = amplitude sin(frequency t + phase) r(t / ramp)."),
    ("vessel.forced.ramp", "0", "s", "Fade-in time of the harmonic motion (continuous acceleration)."),
    ("vessel.forced.file", "required (record)", "", "A motion record (CSV, relative to the scene): a header "
     "row with t and any of surge, sway, heave (m), roll, pitch, yaw (rad); interpolated by a natural cubic "
     "spline (continuous acceleration), the dofs not given held."),
    ("vessel.forced.rate", "required (spin-up)", "rad/s", "The final rate of a spin-up."),
    ("vessel.forced.duration", "required (spin-up)", "s", "The spin-up time."),
    ("vessel.hull.type", '"box"', "", '"box" or "mesh": a hull mesh file, for Capytaine and, closed (deck '
                                      'included), for the nonlinear hydrostatics and stability.'),
    ("vessel.hull.length", "required (box)", "m", "Box hull length, centred on the COG in plan."),
    ("vessel.hull.beam", "required (box)", "m", "Box hull beam."),
    ("vessel.hull.draft", "required (box)", "m", "Box hull draft."),
    ("vessel.hull.kg", "required (box)", "m", "The COG's height above the keel. Traced by the nonlinear "
                                              "hydrostatics only (`identify --fit vessel.hull.kg`)."),
    ("vessel.hull.file", "required (mesh)", "", "The hull mesh (any format meshio or Capytaine reads; triangles "
                                               "and quads), relative to the scene, waterline at z = 0."),
    ("vessel.hull.cog", "[0, 0, 0]", "m", "The COG in the mesh's coordinates. Traced by the nonlinear "
                                          "hydrostatics only (`identify --fit vessel.hull.cog`)."),
    ("vessel.hull.depth", "required (box, nonlinear or stability)", "m", "Box hull: keel to deck, above the "
                                                                          "draft (large angles immerse the deck edge)."),
    ("vessel.hydrodynamics.frequencies", "none", "rad/s", "Ascending, at least 4: the tables below are per "
                                                          "frequency, about the COG."),
    ("vessel.hydrodynamics.added_mass", "none", "kg, kg m, kg m^2", "Radiation added mass per frequency: "
                                                                    "6 values (diagonal) or 6 x 6."),
    ("vessel.hydrodynamics.damping", "none", "N s/m, N s, N m s", "Radiation damping per frequency, same "
                                                                  "shapes."),
    ("vessel.hydrodynamics.added_mass_infinite", "fitted", "kg, kg m, kg m^2", "A_inf (6 or 6 x 6); fitted "
                                                                               "with the memory when absent."),
    ("vessel.hydrodynamics.headings", "none", "rad", "The excitation tables' headings."),
    ("vessel.hydrodynamics.excitation_amplitude", "none", "N/m, N m/m", "Excitation per unit wave amplitude, "
                                                                        "n x h x 6 (or n x 6)."),
    ("vessel.hydrodynamics.excitation_phase", "none", "rad", "Excitation phases, same shape."),
    ("vessel.hydrodynamics.viscous_damping", "none", "N s/m, N m s", "Linear damping (6 or 6 x 6) added to "
                                                                     "the radiation (bilge keels, viscous roll)."),
    ("vessel.hydrodynamics.capytaine", "false", "", "Compute the tables with Capytaine when the run starts "
                                                    "(needs the [hydro] extra)."),
    ("vessel.hydrodynamics.panel_size", "from the hull", "m", "Capytaine's panel size."),
    ("vessel.hydrodynamics.memory_order", "0 (automatic)", "", "Complex pole pairs per fitted entry of the "
                                                               "radiation memory."),
    ("vessel.hydrodynamics.excitation", '"auto"', "", '"table", "froude-krylov" (the box hull), or "auto": '
                                                      "tables when there are, else the box."),
    ("vessel.hydrodynamics.file", "none", "", "A hydrodynamic database: Capytaine NetCDF (.nc) or WAMIT .1 "
                                              "(with .3 and .hst beside it)."),
    ("vessel.hydrodynamics.cog", "the file's", "m", "The COG in the database's coordinates."),
    ("vessel.hydrodynamics.length_scale", "1", "m", "WAMIT's ULEN."),
    # tanks
    ("tanks.name", _REQ, "", "The tank's name (no '.', '[', ']' or '/')."),
    ("tanks.body", '"vessel"', "", "The body that carries the tank: \"vessel\" (or the vessel's `name`) or the "
                                   "name of one of `[[bodies]]`. On a body, the tank is in the body's frame (its "
                                   "`origin` from the body's COG), a finite-element (full or reduced) or multimodal tank with "
                                   "rigid walls; elastic walls are refused there "
                                   "(docs/guide/bodies-and-connections.md)."),
    ("tanks.origin", _REQ, "m", "The min corner of the tank's bounding box in the frame of the body that carries "
                                "it (the vessel's by default), from its COG."),
    ("tanks.size", _REQ, "m", "The bounding box: inner length (x), breadth (y), height (z)."),
    ("tanks.fill_depth", "required (not for mesh)", "m", "Liquid depth at rest from the tank's lowest point."),
    ("tanks.mesh", "required (not for mesh)", "", "Liquid hexahedra along x, y, z."),
    ("tanks.walls", '"rigid"', "", '"rigid"; a [tanks.walls] table makes them elastic.'),
    ("tanks.shape", '"box"', "", '"box", "prismatic", "cylinder" or "mesh".'),
    ("tanks.chamfers", "no cuts", "m", "Prismatic: [[bottom width, height], [top width, height]] corner "
                                       "cuts of the y-z section."),
    ("tanks.chamfers.bottom", "[0, 0]", "m", "Prismatic: [width, height] of the bottom corner cuts."),
    ("tanks.chamfers.top", "[0, 0]", "m", "Prismatic: [width, height] of the top corner cuts."),
    ("tanks.axis", '"x"', "", 'Cylinder: "x" or "y" (horizontal) or "z" (vertical).'),
    ("tanks.file", "required (mesh)", "", "Mesh tank: the liquid at rest as hexahedra (any format meshio "
                                          "reads), relative to the scene."),
    ("tanks.model", '"fem"', "", '"fem" (the linear finite elements) or "multimodal": nonlinear sloshing '
                                 "in a box tank or an upright (axis = \"z\") circular cylinder (every tank of one "
                                 "body the same; on a body, the vessel's tanks multimodal or none)."),
    ("tanks.modes", "6", "", "Multimodal: the free-surface modes, the lowest; with flow = \"3d\" and in a "
                             "cylinder completed to whole degenerate groups (a square's (1, 0), (0, 1) pair, a "
                             "cylinder's cos/sin pairs)."),
    ("tanks.flow", '"2d" ("3d" cylinder)', "", 'Multimodal: "2d", waves along a box\'s length, or "3d", across '
                                              "its whole base (swirl included); a cylinder's are \"3d\"."),
    ("tanks.expansion", '"exact"', "", 'Multimodal: "exact", the liquid\'s integrals evaluated exactly in the '
                                       'modal amplitudes at every step, or "third-order", their Taylor polynomial '
                                       "(the classical third-order modal system: several times cheaper, within a "
                                       "few per cent of the exact tank for crests below a tenth of its length)."),
    ("tanks.fluid.density", "1000.0", "kg/m^3", "Liquid density."),
    ("tanks.fluid.sound_speed", "1500.0", "m/s", "Liquid sound speed."),
    ("tanks.fluid.element", '"rt" for mesh files, baffles, cylinders and chamfered prismatic tanks, else '
                            '"stabilized"', "",
     'The liquid element: "stabilized", the paper\'s literal "paper", or "rt", the face-normal '
     '(Raviart-Thomas) element that does not lock on re-entrant tanks (U-tubes, baffles, hoppers). Left '
     'out: "rt" for a mesh file that is not a box grid, for a tank with baffles, for a cylindrical tank and a prismatic tank whose liquid '
     'touches a chamfer (at full order and on modes), for any prismatic tank on modes ([tanks.reduction]), '
     '"stabilized" otherwise; `check` says which and why. With elastic walls, every '
     'element runs at full order only.'),
    ("tanks.walls.thickness", _REQ, "m", "Wall thickness (one element through it)."),
    ("tanks.walls.mesh", "the liquid mesh", "", "Wall elements along the tank's length, breadth and height."),
    ("tanks.walls.material.young", _REQ, "Pa", "Young's modulus."),
    ("tanks.walls.material.poisson", _REQ, "", "Poisson's ratio, in (-1, 0.5)."),
    ("tanks.walls.material.density", _REQ, "kg/m^3", "Density."),
    ("tanks.reduction.modes", _REQ, "", "The lowest natural modes kept (a degenerate pair is never split)."),
    ("tanks.reduction.static_correction", "true", "", "Add the quasi-static response to every load the rigid "
                                                      "body puts on the liquid."),
    ("tanks.damping.ratio", "0", "", "Damping ratio of every sloshing mode, or a list for the lowest modes "
                                     "(others undamped); in [0, 1)."),
    ("tanks.damping.viscosity", "0", "m^2/s", "Kinematic viscosity: adds each mode's laminar boundary-layer "
                                              "damping."),
    ("tanks.baffles.normal", '"x"', "", 'The plate is perpendicular to "x" or "y".'),
    ("tanks.baffles.position", _REQ, "m", "From the tank's origin along the normal."),
    ("tanks.baffles.from", '"bottom"', "", '"bottom": standing, up to height; "top": hanging, down to height.'),
    ("tanks.baffles.height", _REQ, "m", "Above the tank bottom: the plate's upper edge (bottom) or lower edge "
                                        "(top)."),
    # structures
    ("structures.name", _REQ, "", "The structure's name."),
    ("structures.origin", _REQ, "m", "The block's min corner in the vessel frame."),
    ("structures.size", _REQ, "m", "The block's size along x, y, z."),
    ("structures.mesh", _REQ, "", "Hexahedra along x, y, z."),
    ("structures.attach", _REQ, "", 'The face tied to the vessel: "x-", "x+", "y-", "y+", "z-" or "z+".'),
    ("structures.attach_to", "the vessel", "", "Another structure's name: the face is tied to its "
                                               "coincident nodes."),
    ("structures.frame", '"own"', "", '"own": its own floating frame tied by multipliers; "vessel": its '
                                      "deformation in the vessel's frame."),
    ("structures.stiffening", '"none"', "", '"centrifugal": the geometric stiffness of the stress its spin '
                                            "causes."),
    ("structures.material.young", _REQ, "Pa", "Young's modulus."),
    ("structures.material.poisson", _REQ, "", "Poisson's ratio, in (-1, 0.5)."),
    ("structures.material.density", _REQ, "kg/m^3", "Density."),
    # probes
    ("probes.name", _REQ, "", "The probe's name."),
    ("probes.tank", "one of tank, structure", "", "The tank the probe belongs to."),
    ("probes.structure", "one of tank, structure", "", "The structure the probe belongs to."),
    ("probes.point", _REQ, "m", "Local coordinates from the tank's (structure's) origin."),
    # effects
    ("effects.buoyancy", "true", "", "Hydrostatic restoring."),
    ("effects.liquid", "true", "", "The tank liquid (off: the tanks carry nothing)."),
    ("effects.coriolis", "true", "", "Coriolis terms on the liquid."),
    ("effects.centrifugal", "true", "", "Centrifugal terms on the liquid."),
    ("effects.gravity_turning", "true", "", "Gravity turning with the body in the liquid's frame."),
    ("effects.waves", "true", "", "The wave excitation."),
    ("effects.radiation", "true", "", "Added mass, radiation memory and viscous damping."),
    # waves
    ("waves.type", _REQ, "", '"regular", "jonswap" or "pierson-moskowitz".'),
    ("waves.heading", "0", "rad", "The direction the waves travel to, from +X towards +Y (pi: head seas)."),
    ("waves.amplitude", "required (regular)", "m", "Regular wave amplitude."),
    ("waves.period", "one of period, frequency", "s", "Regular wave period."),
    ("waves.frequency", "one of period, frequency", "rad/s", "Regular wave frequency."),
    ("waves.phase", "0", "rad", "Regular wave: eta = amplitude cos(w t + phase) at the COG's rest position."),
    ("waves.hs", "required (irregular)", "m", "Significant wave height."),
    ("waves.tp", "required (irregular)", "s", "Peak period."),
    ("waves.gamma", "3.3", "", "JONSWAP peak enhancement (>= 1)."),
    ("waves.seed", "0", "", "Random phases and frequencies."),
    ("waves.components", "100", "", "Regular components of an irregular sea."),
    ("waves.frequency_range", "[0.5, 3] x 2 pi / tp", "rad/s", "The components' frequency range."),
    ("waves.ramp", "0", "s", "The wave forces fade in as (1 - cos(pi t / ramp)) / 2."),
    ("waves.depth", "deep water", "m", "Water depth."),
    ("waves.spreading", "0 (long-crested)", "", "cos-2s directional spreading exponent s."),
    ("waves.directions", "15", "", "Headings of a spread sea (odd: one on the mean heading)."),
    # mooring
    ("mooring.name", '"line<i>"', "", "The line's name (result datasets `/mooring/<name>/...`)."),
    ("mooring.body", '"vessel"', "", 'The body the fairlead is on: "vessel", the vessel\'s `name`, or a body of '
                                     '`[[bodies]]` (catenary and lumped lines; guide: Moorings, Lines on a body).'),
    ("mooring.fairlead", _REQ, "m", "The fairlead in the body's frame, from its COG."),
    ("mooring.anchor", _REQ, "m", "The anchor: x, y inertial from the vessel's COG at rest, z from the still-water "
                                  "level (on the seabed at z = -depth, or above it)."),
    ("mooring.length", _REQ, "m", "Unstretched length."),
    ("mooring.weight", _REQ, "N/m", "Submerged weight per unstretched metre (negative: buoyant)."),
    ("mooring.ea", _REQ, "N", "Axial stiffness EA."),
    ("mooring.model", '"catenary"', "", '"catenary": the quasi-static elastic catenary with seabed contact; '
                                        '"lumped": dynamic lumped masses (inertia, added mass, drag, seabed).'),
    ("mooring.segments", "20", "", "Lumped lines: the number of segments (at least 2)."),
    ("mooring.diameter", "0.09", "m", "Lumped lines: the line's hydrodynamic diameter (drag, added mass)."),
    ("mooring.mass", "weight / g + the displaced water", "kg/m", "Lumped lines: the mass per metre in air."),
    ("mooring.cd", "[1.6, 0.1]", "", "Lumped lines: Morison drag coefficients, normal and tangential."),
    ("mooring.ca", "[1.0, 0.0]", "", "Lumped lines: added-mass coefficients, normal and tangential."),
    ("mooring.internal_damping", "-0.8", "N s", "Lumped lines: axial internal damping; negative: that fraction "
                                                  "of each segment's critical damping (MoorDyn's BA)."),
    ("mooring.seabed_stiffness", "3.0e6", "Pa/m", "Lumped lines: the seabed's contact stiffness."),
    ("mooring.seabed_damping", "3.0e5", "Pa s/m", "Lumped lines: the seabed's contact damping."),
    ("mooring.seabed_friction", "0", "", "Friction coefficient of the part on the seabed (anchor on the seabed)."),
    # bodies
    ("bodies.name", _REQ, "", 'The body\'s name (result datasets `/bodies/<name>/...`); not "vessel", "fixed" '
                              "or the vessel's `name`."),
    ("bodies.position", "[0, 0]", "m", "Its COG at rest, horizontally from the vessel's COG at rest, inertial "
                                       "[x, y]; their waterplanes (circles of their areas, or rectangles of their `footprint`) must not overlap."),
    ("bodies.heading", "0", "rad", "Its x axis from the inertial X axis at rest."),
    ("bodies.cog_height", "0 (a box hull: kg - draft)", "m", "Its COG's height above the still-water level at rest (a multibody file's "
                                    "rotation centre's, where it stores one)."),
    ("bodies.footprint", "the circle of the waterplane area", "m", "[length, beam] of its waterplane at rest, "
     "along its heading and across: the overlap check compares this rectangle instead of the circle; the "
     "connection points must lie within it."),
    ("bodies.mass", _REQ, "kg", "The body's mass."),
    ("bodies.inertia", _REQ, "kg m^2", "About its COG, its body axes: 3 diagonal values or 3 x 3."),
    ("bodies.hydrostatics.waterplane_area", "required (the box's with a box hull)", "m^2",
     "A_w: heave restoring rho g A_w."),
    ("bodies.hydrostatics.displaced_volume", "required (the box's with a box hull)", "m^3",
     "Displaced volume at rest (its buoyancy balances its weight there)."),
    ("bodies.hydrostatics.gm_t", "required (the box's with a box hull)", "m", "Transverse metacentric height."),
    ("bodies.hydrostatics.gm_l", "required (the box's with a box hull)", "m", "Longitudinal metacentric height."),
    ("bodies.hydrostatics.moment", '"conservative"', "", 'As `vessel.hydrostatics.moment`.'),
    ("bodies.hydrostatics.model", '"linear"', "", 'As `vessel.hydrostatics.model`: "nonlinear" needs '
                                                  "`[bodies.hull]` (a box with its depth, or a closed mesh); the "
                                                  "waves' pressure on it at the body's place."),
    ("bodies.initial.position", "[0, 0, 0]", "m", "Inertial offset of its COG from its rest position."),
    ("bodies.initial.velocity", "[0, 0, 0]", "m/s", "Inertial velocity of its COG."),
    ("bodies.initial.angular_velocity", "[0, 0, 0]", "rad/s", "Its body frame."),
    ("bodies.initial.roll_pitch_yaw", "[0, 0, 0]", "rad", "Initial attitude from its rest attitude (the yaw is "
                                                          "added to its heading)."),
    # connections
    ("connections.name", '"connection<i>"', "", "The connection's name (result datasets `/connections/<name>/...`)."),
    ("connections.kind", _REQ, "", '"hawser": pulls only | "fender": pushes only | "spring": both.'),
    ("connections.bodies", _REQ, "", 'The two bodies it ties: "vessel" (or the vessel\'s `name`), a body\'s '
                                     'name, or "fixed" as the second (an inertial point).'),
    ("connections.points", _REQ, "m", "One point per body in that body's frame, from its COG; a fixed point "
                                      "inertial, from the vessel's COG at rest. A body's point lies within its hull (the vessel's "
                                      "`hull`, else the `footprint` in plan; none: unchecked)."),
    ("connections.length", _REQ, "m", "Unstretched length (hawser, spring), or the points' distance at first "
                                      "contact (fender)."),
    ("connections.stiffness", "required unless curve", "N/m", "Linear stiffness."),
    ("connections.curve", "required unless stiffness", "m, N", "[[deflection, force], ...], both increasing, "
                                                               "from (0, 0): piecewise linear, extended with its "
                                                               "last slope."),
    ("connections.damping", "0", "N s/m", "Along the line, while in contact for a hawser or a fender."),
    # campaign
    ("campaign.headings", "waves.heading", "rad", "The campaign's headings."),
    ("campaign.seeds", "1", "", "Seeds per cell and heading."),
    ("campaign.duration", "simulation.duration", "s", "Each case's duration."),
    ("campaign.limits.<channel>", "none", "rad, m or N", 'Limit of a channel: roll, pitch (rad), heave, '
                                                         '"probe.<name>" (m), "mooring.<line>" (N, the fairlead '
                                                         'tension about its mean), "<body>.roll", "<body>.pitch" '
                                                         '(rad), "<body>.heave" (m) of a [[bodies]] body, '
                                                         '"connection.<name>" (N, its force about its mean); '
                                                         'quoted or as a dotted key.'),
)
# a body's hull: the vessel's keys, read by the vessel's reader (scene/bodies.py)
KEYS = KEYS + tuple(
    (k.replace("vessel.", "bodies.", 1), d, u, f"As `{k}` (in the body's frame from its COG).")
    for k, d, u, _ in KEYS if k.startswith("vessel.hull."))
# a body's hydrodynamics: the vessel's keys, read by the vessel's reader (scene/bodies.py)
KEYS = KEYS + tuple(
    (k.replace("vessel.", "bodies.", 1), d, u, f"As `{k}`" + (" (a multibody file: this body's block, about its "
                                                              "COG)." if k.endswith(".file") else "."))
    for k, d, u, _ in KEYS if k.startswith("vessel.hydrodynamics."))
