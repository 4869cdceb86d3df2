"""Scenes: one question a user asks flexsat, read from TOML or given as a dict, and validated.

A scene names the hub, the appendages (their truth model and their design model) and mounts, the
fidelity of the truth model, the controllers to tune, the manoeuvre, the outputs wanted, the FMUs
to export and the report to write. :func:`load_scene` reads a TOML file (or a dict, or a path)
into a :class:`Scene`, checking every key once, at the boundary: unknown keys, wrong types,
missing required values, values outside their documented range (table "Ranges"), outputs the
scene cannot produce, and work beyond the documented limits (table "Limits") raise
:class:`SceneError`, one line naming the file, the key path (``appendages[1].beam.diameter``),
the unit, the value (shortened to about 100 characters) and what to do. Inside a Scene every
value is in SI units (angles in rad); the file uses degrees for angles and Hz for the sample
rate, as engineers write them.

Keys (units in the file; ``*`` required)

=====================================  =========  ==============================================
key                                    unit       meaning
=====================================  =========  ==============================================
``title``                              -          free text shown in the report (one line,
                                                  at most limits.string_length characters)
``hub.mass`` *                         kg         hub mass
``hub.inertia`` *                      kg m^2     hub inertia about its centre of mass
``appendages`` *                       -          array of tables, one per appendage (>= 1)
``appendages[i].name``                 -          ASCII identifier (``[A-Za-z_][A-Za-z0-9_]*``,
                                                  at most 64 characters: it names FMU
                                                  variables); default ``appendage<i+1>``
``appendages[i].position``             m          ``[x, y]`` of the attachment point in hub
                                                  axes, from the hub's centre of mass; [0, 0]
``appendages[i].direction``            deg        angle of the appendage's axis from hub +x, or
                                                  a vector ``[x, y]``; default 0
``appendages[i].truth``                -          ``"beam"`` (the distributed beam: uniform,
                                                  with a tip body, stepped or tapered; default
                                                  when one is given), ``"modal"`` (modal data;
                                                  default with them) or ``"chain"``
``appendages[i].design``               -          ``"fit"`` (chain fitted to the structure;
                                                  default with one), ``"chain"`` (the ``chain``
                                                  table; default without beam) or ``"truth"``
                                                  (the truth model itself). An appendage's
                                                  structure is one of the tables ``beam``,
                                                  ``stepped_beam``, ``tapered_beam``, ``modal``
                                                  (or a ``chain`` alone)
``appendages[i].beam.section`` *       -          ``"rod"``, ``"tube"``, ``"rectangular"`` or
                                                  ``"uniform"``
``appendages[i].beam.length`` *        m          beam length
``appendages[i].beam.diameter``        m          rod: diameter
``appendages[i].beam.outer_diameter``  m          tube: outer diameter
``appendages[i].beam.wall_thickness``  m          tube: wall thickness
``appendages[i].beam.width``           m          rectangular: width
``appendages[i].beam.thickness``       m          rectangular: thickness (in the bending plane)
``appendages[i].beam.density``         kg/m^3     rod, tube, rectangular: material density
``appendages[i].beam.youngs_modulus``  Pa         rod, tube, rectangular: Young's modulus
``appendages[i].beam.bending_stiffness``  N m^2   uniform: EJ
``appendages[i].beam.linear_density``  kg/m       uniform: mass per length
``appendages[i].beam.damping_ratio``   -          modal damping ratio in [0, 1) of the
                                                  cantilever (fixed-root) modes; default 0
``appendages[i].tip.mass`` *           kg         a rigid body at the beam's free end (any
                                                  beam, stepped or tapered): its mass
``appendages[i].tip.inertia``          kg m^2     about its own centre of mass: a number
                                                  (about z) in a planar scene, a 3x3 tensor in
                                                  the appendage's axes in a three-axis one;
                                                  default 0
``appendages[i].tip.offset``           m          its centre of mass from the free end: a
                                                  number along the beam (planar), or also
                                                  ``[x, y, z]`` in the appendage's axes (three
                                                  axes); default 0
``appendages[i].stepped_beam.segments`` *  -      array of tables, one per uniform segment from
                                                  the root outward, each with the keys of a
                                                  beam table (section, length, dimensions,
                                                  material) but no damping_ratio
``appendages[i].stepped_beam.damping_ratio``  -   modal damping ratio of its cantilever modes;
                                                  default 0
``appendages[i].tapered_beam.section`` *  -       ``"rod"``, ``"tube"`` or ``"rectangular"``
``appendages[i].tapered_beam.length`` *  m        beam length
``appendages[i].tapered_beam.root_dimensions`` *  m  the section's dimensions at the root (a
                                                  table: ``diameter``; ``outer_diameter``,
                                                  ``wall_thickness``; ``width``, ``thickness``)
``appendages[i].tapered_beam.tip_dimensions`` *  m   the same at the free end (linear between)
``appendages[i].tapered_beam.n_segments``  -      uniform segments approximating it (the
                                                  frequencies' error falls like n**-2);
                                                  default 20
``appendages[i].tapered_beam.density`` *,  as a   as a beam table's (``youngs_modulus`` *,
                                       beam's     ``poisson_ratio``, ``damping_ratio``)
``appendages[i].modal``                -          instead of a beam: the cantilever (root
                                                  clamped) modes of a finite-element model
                                                  (:class:`appendages.ModalAppendage`), truth
                                                  ``"modal"``: all its modes, exact for them
                                                  ("FE-exact"); from one of ``file``,
                                                  ``nastran`` or the numbers below
``appendages[i].modal.file``           -          a modal data file (TOML, units in the file:
                                                  :mod:`appendages.modal_file`), relative to
                                                  the scene's folder
``appendages[i].modal.nastran``        -          a NASTRAN normal-modes solution: an OP2 file
                                                  (needs ``flexsat[nastran]``) or its ``.npz``
                                                  extract (:mod:`appendages.nastran`), with
``appendages[i].modal.root`` *         -          its root grid (clamped there, and only there)
``appendages[i].modal.units`` *        -          the model's ``[length, mass]`` units, e.g.
                                                  ``["mm", "t"]``, ``["in", "slinch"]``
``appendages[i].modal.mass_matrix``    -          its mass matrix: ``.npy`` (dense) or ``.npz``
                                                  (scipy.sparse) over the solution's grids
                                                  (else MEFFMASS or SPCFORCES of the file)
``appendages[i].modal.tip_grid``       -          the grid whose motion is the tip's (tip
                                                  outputs; without it they are zero, warned)
``appendages[i].modal.axes``           -          3x3: the appendage's x, y, z axes (columns)
                                                  in the model's basic system; default identity
``appendages[i].modal.subcase``        -          which subcase's modes; default the only one
``appendages[i].modal.frequencies``    rad/s      numbers in the scene (SI): the cantilever
                                                  frequencies (or ``frequencies_hz`` [Hz])
``appendages[i].modal.participation``  sqrt(kg), sqrt(kg) m  one row per mode: root y, rotation
                                                  z (planar) or x, y, z, rotations (six)
``appendages[i].modal.rigid_mass``     kg, kg m, kg m^2  the rigid mass about the root, 2x2/6x6
``appendages[i].modal.tip_motion``     m/sqrt(kg)  each mode's elastic tip deflection (six
                                                  axes: y, z deflections, twist per mode)
``appendages[i].modal.damping``        -          damping ratio of the modes: one, or one per
                                                  mode (replaces a file's); default the data's,
                                                  0 for a NASTRAN solution
``appendages[i].modal.length``         m          the appendage's extent along x from the root
                                                  (default the data's: a file's, the farthest
                                                  NASTRAN grid)
``appendages[i].modal.n_modes``        -          keep the first n_modes modes (the rest's mass
                                                  joins the residual mass); default all
``appendages[i].truth_chain``          -          a separate truth chain (same keys as
                                                  ``chain``) when ``chain`` is the design model
``appendages[i].fit.n_bodies``         -          bodies of the fitted chain (>= 2); default 3
``appendages[i].fit.match``            -          ``"poles-and-zeros"`` (flexsat's fit, any
                                                  structure), ``"frequencies"`` (the paper's: a
                                                  bare uniform beam only) or a list of both
                                                  (one design model per entry); default
                                                  ``["poles-and-zeros", "frequencies"]`` for a
                                                  bare uniform beam, else
                                                  ``"poles-and-zeros"``
``appendages[i].chain.lengths``        m          explicit chain: body lengths
``appendages[i].chain.masses``         kg         body masses
``appendages[i].chain.inertias``       kg m^2     body inertias about their centres of mass
``appendages[i].chain.hinge_stiffnesses``  N m/rad  one per hinge
``appendages[i].chain.hinge_dampings``  N m s/rad  one per hinge; default 0
``appendages[i].chain.com_offsets``    m          centre of mass from each body's start
``appendages[i].chain.root``           -          ``"rigid"`` (default) or ``"hinged"``
``appendages[i].chain.from_beam``      -          instead of the arrays: ``"rfem"`` (rigid
                                                  finite elements of the appendage's beam,
                                                  stepped or tapered beam, its tip body
                                                  included; not of modal data) with
``appendages[i].chain.n_bodies``       -          its number of bodies (>= 2)
``appendages[i].chain.root_stiffness``  N m/rad   ``root = "hinged"`` with ``from_beam``: the
                                                  drive hinge between mount and first body
``appendages[i].chain.root_damping``   N m s/rad  its damping; default 0
``fidelity.n_modes``                   -          bending modes per truncated beam, or
``fidelity.tolerance``                 -          relative accuracy from which flexsat picks
                                                  n_modes (default 1e-3 when neither is given)
``fidelity.method``                    -          ``"craig-bampton"`` (default), ``"residual"``,
                                                  ``"free-free"``
``fidelity.modes_per_motion.<name>.bending``  -  with ``fidelity.n_modes``: modes the
                                                  truncated beam ``<name>`` keeps beyond
                                                  n_modes (an integer >= 1): what a run from
                                                  ``fidelity.tolerance`` adds for its tip
                                                  outputs, reported in results.json as
                                                  ``fidelity.choice.tip.floors``; with those
                                                  and its n_modes a scene reruns that truth
``fidelity.bandwidth_factor``          -          frequencies up to this multiple of the
                                                  controller bandwidth must match; default 5
``fidelity.prune``                     -          drop modes the inputs cannot excite and the
                                                  outputs cannot see; default true
``controller`` *                       -          the controllers to tune (table)
``controller.types``                   -          list of ``"pd"``, ``"lqr"``; default: the
                                                  tables present (``["pd"]`` if none)
``controller.sample_rate``             Hz         digital controllers (zero-order hold); default
                                                  continuous
``controller.pd.natural_frequency``    rad/s      closed-loop natural frequency, or
``controller.pd.bandwidth``            rad/s      closed-loop -3 dB bandwidth
``controller.pd.damping``              -          closed-loop damping ratio; default 0.7
``controller.pd.roll_off``             rad/s      optional low-pass corner
``controller.pd.notch``                rad/s      optional notch, or ``"first_mode"``
``controller.lqr.attitude_weight`` *   1/rad^2    weight on theta^2
``controller.lqr.rate_weight``         s^2/rad^2  weight on omega^2; default 0
``controller.lqr.torque_weight`` *     1/(N m)^2  weight on torque^2
``controller.lqr.deflection_weight``   1/m^2      weight on each tip deflection (needs
                                                  ``outputs.tip_deflection``)
``controller.lqr.estimator_speed``     -          estimator / regulator bandwidth; default 3
``controller.delay``                   s          loop delay (computation plus transport): the
                                                  torque the plant receives is the command of
                                                  ``delay`` earlier, exactly in every verdict
                                                  (margins, Nyquist, the delay margin) and in
                                                  the simulation; default 0. Above 1 s
                                                  (:data:`controllers.PLAUSIBLE_DELAY`) it is
                                                  run as given and warned about: milliseconds
                                                  given as seconds?
``controller.computation_delay``       -          a digital controller's own computation delay:
                                                  one sample added to ``delay``; default false
``controller.given``                   -          one controller given as state-space numbers
                                                  instead of tuned (``kind``, ``A``, ``B``,
                                                  ``C``, ``D``; units and shapes in
                                                  :mod:`spacecraft.scene.given`)
``manoeuvre.slew_angle`` *             deg        slew angle (non-zero)
``manoeuvre.slew_time`` *              s          duration of the slew profile (the profile
                                                  ends then; rest at the target after)
``manoeuvre.duration``                 s          simulated time; default 3 x slew_time
``manoeuvre.step``                     s          output step; default slew_time / 500 (the
                                                  controller's sample time when digital)
``manoeuvre.profile``                  -          the reference: ``"step"`` (the cycloid of
                                                  theta_ref alone; default), ``"bang-coast-bang"``
                                                  (time-optimal under torque and rate limits),
                                                  ``"smooth"`` (jerk-limited, 7 segments) or
                                                  ``"shaped"`` (a base profile convolved with
                                                  an input shaper on the design model's modes)
``manoeuvre.feedforward``              -          feed the profile's rate reference and torque
                                                  J alpha_ref to controllers tuned to take them;
                                                  default false (not with ``"step"``)
``manoeuvre.torque_limit``             N m        the profile's rigid-body torque limit (its
                                                  acceleration limit times the spacecraft's
                                                  inertia); default none
``manoeuvre.rate_limit``               deg/s      the profile's rate limit; default none
``manoeuvre.jerk_limit``               deg/s^3    ``"smooth"`` (or a smooth base): jerk limit
``manoeuvre.shaper.kind``              -          ``"shaped"``: ``"zv"`` or ``"zvd"`` (default;
                                                  the shortest that holds frequency_error when
                                                  that is given)
``manoeuvre.shaper.modes``             -          the lowest flexible modes of each design
                                                  model to shape (1 to 8); default 1
``manoeuvre.shaper.base``              -          ``"bang-coast-bang"`` (default) or
                                                  ``"smooth"``
``manoeuvre.shaper.frequency_error``   -          the robustness asked: the residual vibration
                                                  stays below ``tolerance`` for modes within
                                                  +- this fraction of the design's frequency
``manoeuvre.shaper.tolerance``         -          that residual vibration, a fraction of the
                                                  unshaped one; default 0.05
``manoeuvre.disturbance.input``        -          ``"disturbance_torque"`` [N m],
                                                  ``"force_x"``, ``"force_y"`` [N] or
                                                  ``"<name>_tip_force"`` [N]
``manoeuvre.disturbance.amplitude``    N, N m     pulse amplitude (non-zero)
``manoeuvre.disturbance.start``        s          pulse start; default 0
``manoeuvre.disturbance.length``       s          pulse length; default to the end
``outputs.tip_deflection``             -          tip-deflection outputs; default false
``outputs.root_loads``                 -          root force and moment outputs; default false
``outputs.exact_reference``            -          frequency-domain references through the exact
                                                  beam W(s) (Bode plot, exact-loop verdict);
                                                  default false; needs a beam truth
``export.fmu``                         -          export FMUs; default false
``export.systems``                     -          any of ``"plant"``, ``"controller"``,
                                                  ``"closed_loop"``; default all three
``export.reference_files``             -          FMI cross-check files; default true
``export.step``                        s          FMU communication step; default manoeuvre
                                                  step (a digital controller's FMU samples at
                                                  its own sample time whatever the step)
``export.fmi_version``                 -          ``"2.0"`` (default), ``"3.0"`` or a list of
                                                  both (one set of FMUs per version)
``export.sources_only``                -          FMUs without a binary (C sources and build
                                                  description only); default false
``export.ssp``                         -          also an SSP file per controller connecting
                                                  plant and controller FMUs; needs both in
                                                  ``export.systems``; default false
``report.plots``                       -          true (all), false, or a list of ``"slew"``
                                                  (responses), ``"loop"`` (Bode and Nyquist of
                                                  L(j omega)), ``"poles"`` (closed-loop poles),
                                                  ``"W"`` (W(s) of every appendage),
                                                  ``"profile"`` (the reference profile; with
                                                  true for a flown profile only), ``"wheels"``
                                                  (wheel torque and momentum against their
                                                  limits; with true when there are wheels); default
                                                  false (``"bode"``, ``"pole_zero"``: old names
                                                  of ``"W"``, ``"poles"``)
``report.equivalence``                 -          equivalence table of fitted chains; default
                                                  true when a chain is fitted
``report.timeseries``                  -          the responses as CSV files beside
                                                  results.json; default true
``simulator.name``                     -          ``"flexsat"`` (default) or ``"basilisk"``:
                                                  the manoeuvre also in Basilisk, on the design
                                                  chains (needs ``flexsat[basilisk]``)
``simulator.sample_rate``              Hz         Basilisk's flight-software rate; default the
                                                  controller's, else 30 per period of the
                                                  crossover or of the controller's fastest
                                                  pole where the loop has gain
``simulator.dt``                       s          Basilisk's RK4 step (divides the sample
                                                  time; refused beyond RK4's stability limit,
                                                  naming the largest stable step); default
                                                  accurate up to the flight software's Nyquist
                                                  frequency and stable above, a chain's
                                                  torsion above its sampling frequency held
                                                  rigid (the report says what it costs)
``simulator.reaction_wheel.spin_inertia``  kg m^2  torque through a reaction wheel about z
                                                  (three-axis: one on each hub axis)
``simulator.reaction_wheel.max_torque``  N m      its motor torque limit; default none
``simulator.reaction_wheel.max_speed``  rad/s     its speed limit; default none
``wheels.torque_limit`` *              N m        reaction wheels fly the torque (planar: one
                                                  wheel about z): each wheel's motor torque
                                                  limit (a number, or one per wheel)
``wheels.momentum_limit`` *            N m s      each wheel's momentum limit J_s Omega_max
``wheels.spin_inertia``                kg m^2     each wheel's rotor inertia (its speed is
                                                  reported); default none
``wheels.viscous_friction``            N m s/rad  c_v Omega (needs spin_inertia); default 0
``wheels.coulomb_friction``            N m        c_c sign(Omega); default 0
``wheels.saturation``                  -          ``"scale"`` (the torque vector scaled to the
                                                  limits, its direction kept; default) or
                                                  ``"clip"`` (each wheel alone, as Basilisk)
``sensors.attitude_density``           rad/       attitude sensor's white angle noise, the
                                       sqrt(Hz)   square root of its two-sided intensity (one
                                                  value, or three: x, y, z), or
``sensors.attitude_rms``               rad        its rms per sample, with
``sensors.attitude_rate``              Hz         its sample rate (density = rms / sqrt(rate))
``sensors.angle_random_walk``          rad/       gyro's white rate noise N (IEEE 952)
                                       sqrt(s)
``sensors.bias_instability``           rad/s      gyro's Gauss-Markov bias, stationary sigma
``sensors.bias_correlation_time``      s          its correlation time (with bias_instability)
``sensors.rpe_window`` *               s          window of the relative pointing error (and
                                                  of the MPE); a digital controller's: whole
                                                  samples
``sensors.placement``                  -          where t lies in its window: ``"random"``
                                                  (uniform; default) or ``"end"``
``sensors.probability``                -          the level the pointing figures are also
                                                  given at (two-sided Gaussian); default 0.9973
``limits.<name>``                      -          raise (or lower) a work limit (table "Limits")
**three axes** (``hub.inertia`` a 3x3)
``hub.inertia``                        kg m^2     ``[[Jxx, Jxy, Jxz], [..], [..]]``: symmetric
                                                  positive definite, a body's (largest
                                                  principal moment <= sum of the other two),
                                                  about the hub's centre of mass, hub axes;
                                                  makes the scene three-axis
``appendages[i].position``             m          ``[x, y, z]``; default [0, 0, 0]
``appendages[i].orientation``          deg        Euler angles of the appendage's axes (x along
                                                  it); default [0, 0, 0]; replaces direction
``appendages[i].orientation_sequence``  -         ``"ZYX"`` (default: yaw, pitch, roll) or any
                                                  scipy sequence (upper case intrinsic)
``appendages[i].beam.poisson_ratio``   -          sections: G = E / (2 (1 + nu)) for torsion;
                                                  default 0.3 (a section is needed: torsion
                                                  and axial motion; no ``"uniform"``); planar
                                                  scenes refuse it
``appendages[i].chain``                -          ``from_beam = "rfem"`` (the 3-D rigid
                                                  finite elements of the beam, a rigid root)
                                                  or the arrays (``root = "hinged"``: every
                                                  per-joint array one entry longer, its first
                                                  the joint between mount and body 1, sprung
                                                  in each motion the arrays spring):
                                                  ``lengths``, ``masses``,
                                                  ``com_offsets`` shared by every motion,
                                                  ``inertias``, ``hinge_stiffnesses``,
                                                  ``hinge_dampings`` of x-y bending (about the
                                                  body's local z) and
``appendages[i].chain.inertias_y``     kg m^2     x-z bending: inertias about each body's
                                                  local y; default ``inertias``
``appendages[i].chain.hinge_stiffnesses_y``  N m/rad  x-z bending, one per joint; default
                                                  ``hinge_stiffnesses``
``appendages[i].chain.hinge_dampings_y``  N m s/rad  x-z bending, one per joint; default
                                                  ``hinge_dampings``
``appendages[i].chain.torsional_inertias``  kg m^2  each body's moment about the chain's
                                                  axis (required with the arrays)
``appendages[i].chain.torsion_stiffnesses``  N m/rad  one per joint; default none
                                                  (torsionally rigid joints)
``appendages[i].chain.torsion_dampings``  N m s/rad  one per joint (needs
                                                  ``torsion_stiffnesses``); default 0
``appendages[i].chain.axial_stiffnesses``  N/m    one per joint; default none (inextensible)
``appendages[i].chain.axial_dampings``  N s/m     one per joint (needs
                                                  ``axial_stiffnesses``); default 0
``fidelity.n_modes``                   -          modes per uniform beam, the lowest of all
                                                  its motions together; when chosen from
                                                  ``fidelity.tolerance`` with
                                                  ``outputs.tip_deflection``: the modes beyond
                                                  the lowest mode of every motion a tip output
                                                  sees (both bending planes, torsion; with
                                                  ``outputs.root_loads`` also axial), which
                                                  are kept however stiff
``fidelity.modes_per_motion``          -          with ``fidelity.n_modes``, a table (may be
                                                  empty): the truncations then keep the lowest
                                                  mode of both bending planes and torsion (and
                                                  axial with ``outputs.root_loads``), as a run
                                                  from ``fidelity.tolerance`` with tip outputs
                                                  does, whatever this scene reports, and
``fidelity.modes_per_motion.<name>.<motion>``  -  per truncated beam ``<name>``, the modes
                                                  that run's tip-output rule adds (results.json
                                                  ``fidelity.choice.tip.floors``; with those
                                                  and its n_modes a scene reruns that truth),
                                                  an integer >= 1: a uniform beam's ``xy``,
                                                  ``xz``, ``torsion``, ``axial``: at least
                                                  this many modes of that motion; a beam with
                                                  a tip body or segments: ``coupled``, lowest
                                                  modes kept beyond n_modes
``wheels.spin_axes``                   -          ``[[x, y, z], ...]``: each wheel's spin axis
                                                  (hub axes; they must span x, y, z), or
``wheels.pyramid.cant_angle``          deg        four wheels about +z, each at this angle from
                                                  it; default 54.7356 (arccos(1/sqrt(3)))
``wheels.pyramid.azimuth``             deg        the first wheel's azimuth from +x; default 0
``manoeuvre.slew_axis`` *              -          ``"x"``, ``"y"``, ``"z"`` or ``[x, y, z]`` (hub
                                                  axes): the eigen-axis slew of slew_angle
``manoeuvre.disturbance.input``        -          ``"disturbance_torque"`` [N m] or
                                                  ``"force"`` [N] along ``axis``; or one axis'
                                                  ``"disturbance_torque_x"``.. ``"force_z"``,
                                                  ``"<name>_tip_force_y"``, ``_z`` [N] (the
                                                  appendage's axes)
``manoeuvre.disturbance.axis``         -          ``"x"``, ``"y"``, ``"z"`` or ``[x, y, z]``
                                                  (hub axes): the direction of
                                                  ``disturbance_torque`` or ``force``
(every other key as in a planar scene; a planar scene refuses the three-axis chain keys by
name; a given controller takes the three axes'
signals, :mod:`spacecraft.scene.given`; the manoeuvre as flown is the eigen-axis slew about the
slew axis, with the wheels' spin axes or a pyramid and noise per axis)
=====================================  =========  ==============================================

Ranges (SI units, the file's deg and Hz where it uses them; ``|x|``: either sign)

====================================================  ===================  ==================
keys                                                  accepted             unit
====================================================  ===================  ==================
``hub.mass``                                          1e-3 .. 1e7          kg
``hub.inertia``                                       1e-6 .. 1e10         kg m^2
``appendages[i].position``                            |x| <= 1e3           m
``appendages[i].direction`` (an angle)               |x| <= 360           deg
``appendages[i].direction`` (a vector)               |x| <= 1e6           -
``hub.inertia`` (a 3x3 tensor, entries)               |x| <= 1e10          kg m^2
``appendages[i].orientation``                         |x| <= 360           deg
``beam.poisson_ratio``                                0 .. 0.5 (excluded)  -
``manoeuvre.slew_axis``, ``disturbance.axis``         |x| <= 1e6           -
``beam.length``                                       1e-2 .. 1e3          m
``beam.diameter``, ``outer_diameter``, ``width``,     1e-5 .. 10, and at   m
``thickness``                                         most the length
                                                      (except width)
``beam.wall_thickness``                               1e-6 .. outer/2      m
``beam.density``                                      1 .. 1e5             kg/m^3
``beam.youngs_modulus``                               1e5 .. 1e13          Pa
``beam.bending_stiffness``                            1e-6 .. 1e12         N m^2
``beam.linear_density``                               1e-6 .. 1e5          kg/m
``beam.damping_ratio``                                0 .. < 1             -
``tip.mass``                                          0 or 1e-6 .. 1e7     kg
``tip.inertia`` (a number)                            0 or 1e-12 .. 1e10   kg m^2
``tip.inertia`` (a 3x3 tensor, entries)               |x| <= 1e10          kg m^2
``tip.offset``                                        |x| <= 1e3           m
``tapered_beam.n_segments``                           1 .. limits.bodies   -
``modal.frequencies`` (each; the data's too)          1e-4 .. 1e7          rad/s
``modal.frequencies_hz``                              1e-5 .. 2e6          Hz
``modal.participation``, ``tip_motion`` (entries)     |x| <= 1e8           SI
``modal.rigid_mass`` (entries)                        |x| <= 1e10          kg, kg m, kg m^2
``modal.axes`` (entries)                              |x| <= 1             -
``modal.damping``                                     0 .. < 1             -
``modal.length`` (given or the data's)                1e-2 .. 1e3          m
first bending frequency of a beam (derived; of a      1e-4 .. 1e5          rad/s
stepped or tapered beam: its segments assembled)
``chain.lengths``                                     1e-3 .. 1e3          m
``chain.masses``                                      1e-6 .. 1e7          kg
``chain.inertias``                                    0 or 1e-12 .. 1e10   kg m^2
``chain.hinge_stiffnesses``, ``root_stiffness``       1e-6 .. 1e12         N m/rad
``chain.hinge_dampings``, ``root_damping``            0 or 1e-12 .. 1e12   N m s/rad
``chain.com_offsets``                                 0 .. body length     m
``chain.inertias_y``                                  0 or 1e-12 .. 1e10   kg m^2
``chain.torsional_inertias``                          1e-12 .. 1e10        kg m^2
``chain.hinge_stiffnesses_y``, ``torsion_stiffnesses``  1e-6 .. 1e12       N m/rad
``chain.hinge_dampings_y``, ``torsion_dampings``      0 or 1e-12 .. 1e12   N m s/rad
``chain.axial_stiffnesses``                           1e-6 .. 1e15         N/m
``chain.axial_dampings``                              0 or 1e-12 .. 1e12   N s/m
``fidelity.tolerance``                                1e-12 .. 0.5         -
``fidelity.bandwidth_factor``                         1 .. 1e3             -
``controller.sample_rate``                            1e-3 .. 1e6          Hz
``controller.pd.natural_frequency``, ``bandwidth``    1e-5 .. 1e3          rad/s
``controller.pd.damping``                             1e-3 .. 10           -
``controller.pd.roll_off``, ``notch``                 1e-5 .. 1e6          rad/s
``controller.lqr.attitude_weight``                    1e-12 .. 1e12        1/rad^2
``controller.lqr.torque_weight``                      1e-12 .. 1e12        1/(N m)^2
``controller.lqr.rate_weight``                        0 or 1e-12 .. 1e12   s^2/rad^2
``controller.lqr.deflection_weight``                  0 or 1e-12 .. 1e12   1/m^2
``controller.lqr.estimator_speed``                    0.1 .. 100           -
rigid-body LQR frequency (q / (r J^2))^(1/4), derived 1e-5 .. 1e3          rad/s
``manoeuvre.slew_angle``                              1e-6 <= |x| <= 360   deg
``manoeuvre.slew_time``                               1e-3 .. 1e8          s
``manoeuvre.duration``                                1e-3 .. 1e10         s
``manoeuvre.step``, ``export.step``                   1e-9 .. 1e6          s
``manoeuvre.disturbance.amplitude``                   1e-12 <= |x| <= 1e9  N, N m
``manoeuvre.disturbance.start``                       0 .. < duration      s
``manoeuvre.disturbance.length``                      1e-9 .. 1e10         s
``simulator.sample_rate``                             1e-3 .. 1e6          Hz
``simulator.dt``                                      1e-9 .. 1e3          s
``simulator.reaction_wheel.spin_inertia``             1e-9 .. 1e6          kg m^2
``simulator.reaction_wheel.max_torque``               1e-9 .. 1e6          N m
``simulator.reaction_wheel.max_speed``                1e-3 .. 1e6          rad/s
``controller.delay``                                  0 or 1e-9 .. 1e3     s
``manoeuvre.torque_limit``                            1e-9 .. 1e6          N m
``manoeuvre.rate_limit``                              1e-6 .. 1e3          deg/s
``manoeuvre.jerk_limit``                              1e-9 .. 1e6          deg/s^3
``shaper.frequency_error``, ``shaper.tolerance``      1e-6 .. < 1          -
``wheels.torque_limit``                               1e-9 .. 1e6          N m
``wheels.momentum_limit``                             1e-9 .. 1e9          N m s
``wheels.spin_inertia``                               1e-9 .. 1e6          kg m^2
``wheels.viscous_friction``                           0 or 1e-12 .. 1e6    N m s/rad
``wheels.coulomb_friction``                           0 or 1e-12 .. 1e6    N m
``wheels.spin_axes``                                  |x| <= 1e6           -
``wheels.pyramid.cant_angle``                         1e-3 .. < 90         deg
``wheels.pyramid.azimuth``                            |x| <= 360           deg
``sensors.attitude_density``                          0 or 1e-15 .. 1      rad/sqrt(Hz)
``sensors.attitude_rms``                              0 or 1e-15 .. 1      rad
``sensors.attitude_rate``                             1e-3 .. 1e6          Hz
``sensors.angle_random_walk``                         0 or 1e-15 .. 1      rad/sqrt(s)
``sensors.bias_instability``                          0 or 1e-15 .. 1      rad/s
``sensors.bias_correlation_time``                     1e-6 .. 1e9          s
``sensors.rpe_window``                                1e-6 .. 1e8          s
``sensors.probability``                               1e-6 .. < 1          -
====================================================  ===================  ==================

Limits (work a scene may ask for; :mod:`spacecraft.scene.limits` has the measurements behind them).
Raise one explicitly where you really want more: a ``[limits]`` table in the scene
(``[limits]`` / ``modes = 800``) or ``--limit modes=800`` on the command line (which wins).

=================  ===========  ==================================================================
limit              default      bounds
=================  ===========  ==================================================================
modes              500          ``fidelity.n_modes``; the search from ``fidelity.tolerance``
                                tries at most 40 modes, or this limit if lower (see
                                ``spacecraft.design.fidelity.MAX_MODES``)
bodies             500          bodies per chain (arrays, ``chain.n_bodies``)
fit_bodies         14           ``fit.n_bodies`` (appendages' limit: the range the fit is
                                benchmarked and tested on)
appendages         64           ``appendages`` entries
states             1200         states of the largest closed loop (estimated upper bound)
samples            1e7          samples per simulation, ``duration / step + 1`` (and of FMU
                                reference files); a digital loop's count 20 each
memory             2 GiB        bytes held by the time responses (estimated upper bound)
string_length      4096         characters of ``title``
file_size          1 MiB        bytes of a scene file (``--limit`` only)
basilisk_seconds   600 s        estimated wall time of one Basilisk run (``simulator.name =
                                "basilisk"``; RK4 steps times the chain's bodies cubed)
=================  ===========  ==================================================================

References
----------
.. [1] TOML v1.0.0, https://toml.io/en/v1.0.0 (read with :mod:`tomllib`).
.. [2] Belonozhko et al. 2009 (PAPER.md): the default scene's steel rod.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
import numbers
import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from appendages.unit_slips import damping_in_percent, modulus_in_megapascals, radians_in_degrees

from appendages.errors import FlexsatError
from appendages.units import LENGTH_UNITS, MASS_UNITS

from .limits import (DIGITAL_SAMPLE_COST, LIMIT_UNITS, REAL_LIMITS, Limits, estimate_cost,
                     library_limits)
from .reader import (BEAM_FREQUENCY_RANGE, NAME_LENGTH, RANGES, SceneError, BETA1_L,
                           NAME_PATTERN, SceneReader, value_kind, quoted_choices, shown_value, shorten, suggestion)
from .given import read_given
from .specs import SensorsSpec, ShaperSpec, WheelsSpec  # noqa: F401  (public through this module)
from .flown import (MANOEUVRE_KEYS, check_flown_scene, flown_plots, read_delay, read_profile,
                    read_sensors, read_wheels)
from .specs import (CONTROLLERS, EXPORTABLE, FMI_VERSIONS, MATCHES, METHODS, PLOT_ALIASES,
                          PLOTS, SECTIONS, SIMULATORS, AppendageSpec, BeamSpec, ChainSpec,
                          ControllerSpec, DisturbanceSpec, ExportSpec, FidelitySpec, FitSpec,
                          HubSpec, LQRSpec, ManoeuvreSpec, OutputsSpec, PDSpec,
                          ModalSpec, ReactionWheelSpec, ReportSpec, Scene, SimulatorSpec,
                          SteppedBeamSpec, TAPERED_SECTIONS, TaperedBeamSpec, TipSpec,
                          scene_dict)

__all__ = [
    "PINNED_MOTIONS",
    "SceneError",
    "Scene",
    "HubSpec",
    "BeamSpec",
    "ChainSpec",
    "FitSpec",
    "AppendageSpec",
    "FidelitySpec",
    "PDSpec",
    "LQRSpec",
    "ControllerSpec",
    "DisturbanceSpec",
    "ManoeuvreSpec",
    "OutputsSpec",
    "ExportSpec",
    "ReportSpec",
    "SimulatorSpec",
    "ReactionWheelSpec",
    "ShaperSpec",
    "WheelsSpec",
    "SensorsSpec",
    "load_scene",
    "default_scene",
    "example_scenes",
    "scene_path",
    "scene_dict",
    "models_scene",
    "read_limits",
    "read_beam_table",
    "with_overrides",
    "RANGES",
    "BEAM_FREQUENCY_RANGE",
    "NAME_LENGTH",
    "PLOTS",
]


_SECTION_KEYS = {
    "rod": ("diameter",),
    "tube": ("outer_diameter", "wall_thickness"),
    "rectangular": ("width", "thickness"),
    "uniform": ("bending_stiffness", "linear_density"),
}
_SECTION_RANGES = {"diameter": "beam.section", "outer_diameter": "beam.section",
                   "wall_thickness": "beam.wall_thickness", "width": "beam.section",
                   "thickness": "beam.section", "bending_stiffness": "beam.bending_stiffness",
                   "linear_density": "beam.linear_density"}
#: Segments of a tapered beam when ``tapered_beam.n_segments`` is not given (the frequencies'
#: error falls like n_segments**-2: appendages.stepped).
TAPERED_SEGMENTS = 20

# section dimensions in the bending plane: a beam is longer than it is deep
_IN_PLANE = ("diameter", "outer_diameter", "thickness")


def _section_properties(section: str, d: dict, density, youngs) -> tuple[float, float]:
    """EJ [N m^2] and rho A [kg/m] of a section (the formulas of appendages.Beam's
    constructors)."""
    if section == "uniform":
        return d["bending_stiffness"], d["linear_density"]
    if section == "rod":
        area, second_moment = math.pi * d["diameter"]**2 / 4, math.pi * d["diameter"]**4 / 64
    elif section == "tube":
        outer, inner = d["outer_diameter"], d["outer_diameter"] - 2 * d["wall_thickness"]
        area = math.pi * (outer**2 - inner**2) / 4
        second_moment = math.pi * (outer**4 - inner**4) / 64
    else:
        area, second_moment = d["width"] * d["thickness"], d["width"] * d["thickness"]**3 / 12
    return youngs * second_moment, density * area


def _read_beam(r: SceneReader, data, path: str, *, segment: bool = False,
               tip: TipSpec | None = None, damping: float | None = None) -> BeamSpec:
    """A beam table (``segment``: one segment of a stepped beam, whose damping ratio is the
    stepped beam's ``damping``, without its own frequency check)."""
    t = r.table(data, path)
    section = r.choice(t, "section", path, SECTIONS)
    length = r.number(t, "length", path, "beam.length")
    dims = {key: r.number(t, key, path, _SECTION_RANGES[key]) for key in _SECTION_KEYS[section]}
    density = youngs = None
    if section != "uniform":
        density = r.number(t, "density", path, "beam.density")
        youngs = _with_unit_hint(lambda: r.number(t, "youngs_modulus", path,
                                                  "beam.youngs_modulus"),
                                 t.get("youngs_modulus"), _modulus_hint)
        r.warn(f"{path}.youngs_modulus", modulus_in_megapascals(youngs, density))
    if segment:
        if "damping_ratio" in t:
            raise r.error(f"{path}.damping_ratio", "a segment has no damping ratio of its own: "
                          "the stepped beam's damping_ratio [-] damps its cantilever modes "
                          "(give it beside segments)")
        damping = 0.0 if damping is None else damping
    else:
        damping = _read_damping_ratio(r, t, path)
    allowed = {"section", "length", *_SECTION_KEYS[section]} | (set() if segment
                                                                 else {"damping_ratio"})
    if section != "uniform":
        allowed |= {"density", "youngs_modulus", "poisson_ratio"}
    if "poisson_ratio" in t and not getattr(r, "three_axis", False):
        raise r.error(f"{path}.poisson_ratio", "applies to three-axis scenes (the shear modulus "
                      "G = E / (2 (1 + nu)) of the beam's torsion); a planar scene's beams "
                      "bend in the hub's plane only")
    poisson = (r.number(t, "poisson_ratio", path, "beam.poisson_ratio", default=0.3)
               if section != "uniform" else 0.3)
    for key in list(t):
        if key in _SECTION_RANGES or key in ("density", "youngs_modulus"):
            raise r.error(f"{path}.{key}", f"does not apply to section {section!r}; it needs "
                          + ", ".join(sorted(allowed - {'section'})))
        if key == "tip":
            raise r.error(f"{path}.tip", "a tip body is a table of the appendage "
                          "(appendages[i].tip: mass, inertia, offset), beside its beam")
    r.done(t, path, allowed)
    _check_section_shape(r, path, section, length, dims)
    if not segment:
        bending_stiffness, linear_density = _section_properties(section, dims, density, youngs)
        omega_1 = BETA1_L**2 * math.sqrt(bending_stiffness / linear_density) / length**2
        _check_first_frequency(r, path, omega_1, "from length, section and material")
    return BeamSpec(section, length, tuple(dims.items()), density, youngs, damping, poisson, tip)


def _read_damping_ratio(r: SceneReader, t: dict, path: str) -> float:
    """``damping_ratio`` [-] of a beam (default 0), with its unit-slip hint and warning."""
    damping = _with_unit_hint(lambda: r.number(t, "damping_ratio", path, "beam.damping_ratio",
                                               default=0.0),
                              t.get("damping_ratio"), _percent_hint)
    r.warn(f"{path}.damping_ratio", damping_in_percent(damping))
    return damping


def _check_section_shape(r: SceneReader, path: str, section: str, length: float, dims: dict):
    """A tube's wall at most half its diameter; a beam no deeper than it is long."""
    if section == "tube" and dims["wall_thickness"] > dims["outer_diameter"] / 2:
        raise r.error(f"{path}.wall_thickness", "must be at most outer_diameter/2 = "
                      f"{dims['outer_diameter'] / 2:g} [m]; got {dims['wall_thickness']:g}")
    for key in _IN_PLANE:
        if key in dims and dims[key] > length:
            raise r.error(f"{path}.{key}", f"must not exceed the beam's length {length:g} [m] "
                          f"(a beam is slender); got {dims[key]:g}")


def _check_first_frequency(r: SceneReader, path: str, omega_1: float, origin: str) -> None:
    """Refuse a beam whose first free-free bending frequency [rad/s] lies outside
    BEAM_FREQUENCY_RANGE."""
    lo, hi = BEAM_FREQUENCY_RANGE
    if not lo <= omega_1 <= hi:
        raise r.error(path, f"first bending frequency {omega_1:.3g} rad/s ({origin}) lies "
                      f"outside [{lo:g}, {hi:g}] rad/s, the range flexsat's models are verified "
                      "for; check the units of length, section and material")


def _read_tip(r: SceneReader, data, path: str) -> TipSpec:
    """``appendages[i].tip``: a rigid body at the beam's free end."""
    t = r.table(data, path)
    three_axis = getattr(r, "three_axis", False)
    mass = r.number(t, "mass", path, "tip.mass")
    # default: a point mass (three axes: the zero tensor)
    value, full = r.take(t, "inertia", path, ((0.0,) * 3,) * 3 if three_axis else 0.0)
    if three_axis:
        if not isinstance(value, (list, tuple)):
            raise r.error(full, "must be a 3x3 array [kg m^2] in a three-axis scene: the body's "
                          "inertia tensor about its own centre of mass, appendage axes; got "
                          f"{value_kind(value)}")
        inertia = _read_inertia_tensor(r, value, full, kind="tip.inertia tensor",
                                       about="about the body's own centre of mass, appendage "
                                             "axes")
    else:
        if isinstance(value, (list, tuple)):
            raise r.error(full, "must be a number [kg m^2] in a planar scene: the body's moment "
                          "of inertia about z through its own centre of mass")
        inertia = r.check_number(value, full, "tip.inertia")
    offset_value, full = r.take(t, "offset", path, 0.0)
    if isinstance(offset_value, (list, tuple)):
        if not three_axis:
            raise r.error(full, "must be a number [m] in a planar scene: the body's centre of "
                          "mass beyond the free end, along the appendage's x axis (an offset "
                          "across the axis couples axial motion, which a planar model has not)")
        offset = r.vector({"offset": offset_value}, "offset", path, "tip.offset", size=3)
    else:
        offset = r.check_number(offset_value, full, "tip.offset")
    r.done(t, path, {"mass", "inertia", "offset"})
    spec = TipSpec(mass, inertia, offset)
    try:
        spec.build()
    except (TypeError, ValueError) as exc:
        raise r.error(path, str(exc)) from None
    return spec


#: The tables that give an appendage's structure (one per appendage).
STRUCTURES = ("beam", "stepped_beam", "tapered_beam", "modal")

#: Keys of a ``modal`` table by source; ``damping``, ``length`` and ``n_modes`` go with any.
_MODAL_KEYS = {"file": ("file",),
               "nastran": ("nastran", "root", "units", "mass_matrix", "tip_grid", "axes",
                           "subcase"),
               "inline": ("frequencies", "frequencies_hz", "participation", "rigid_mass",
                          "tip_motion")}


_MODAL_ORIGINS = {"file": "a modal data file", "nastran": "a NASTRAN solution",
                  "inline": "numbers in the scene"}


def _data_path(r: SceneReader, value, full: str, suffixes: tuple) -> str:
    """A data file named in the scene: a string, relative to the scene's folder (or absolute),
    an existing file with one of ``suffixes``; returned absolute."""
    if not isinstance(value, str) or not value:
        raise r.error(full, f"must be a file path (a string, relative to the scene's folder); "
                      f"got {value_kind(value)}")
    base = getattr(r, "base", None) or Path.cwd()
    path = (Path(base) / value).resolve()
    if not path.is_file():
        raise r.error(full, f"no such file: {shorten(str(path))} (a path relative to the "
                      f"scene's folder {shorten(str(base))})")
    if not path.name.lower().endswith(suffixes):
        raise r.error(full, f"must be a {' or '.join(suffixes)} file; got {shown_value(value)}")
    return str(path)


def _matrix(r: SceneReader, t: dict, key: str, path: str, kind: str, *, rows: int | None = None,
            columns: tuple = ()) -> tuple | None:
    """An array of rows of numbers of the range ``RANGES[kind]`` (``columns``: the accepted
    row lengths), or None when absent."""
    value, full = r.take(t, key, path, None)
    if value is None:
        return None
    unit = RANGES[kind].unit
    if not isinstance(value, (list, tuple)) or not value or not all(
            isinstance(row, (list, tuple)) for row in value):
        raise r.error(full, f"must be an array of rows of numbers [{unit}]; got {value_kind(value)}")
    r.check_limit(full, len(value), "modes", f"an array of {len(value)} rows")
    if rows is not None and len(value) != rows:
        raise r.error(full, f"must have {rows} rows [{unit}]; got {len(value)}")
    width = len(value[0])
    if width not in columns or any(len(row) != width for row in value):
        raise r.error(full, f"must have rows of {' or '.join(map(str, columns))} numbers "
                      f"[{unit}], all alike; got rows of {sorted({len(row) for row in value})}")
    return tuple(tuple(r.check_number(v, f"{full}[{i}][{j}]", kind) for j, v in enumerate(row))
                 for i, row in enumerate(value))


def _read_modal(r: SceneReader, data, path: str) -> ModalSpec:
    """``appendages[i].modal``: the cantilever modes of a finite-element model, from a modal
    data file, a NASTRAN solution or the numbers given here."""
    t = r.table(data, path)
    three_axis = getattr(r, "three_axis", False)
    sources = [k for k in ("file", "nastran", "frequencies", "frequencies_hz") if k in t]
    if not sources:
        raise r.error(path, "needs its data: file = \"modes.toml\" (a modal data file, units "
                      "in the file), nastran = \"modes.op2\" (a NASTRAN normal-modes solution, "
                      "or its .npz extract) or the numbers (frequencies [rad/s] or "
                      "frequencies_hz [Hz], participation, rigid_mass)" + suggestion(
                          next(iter(t), ""), ("file", "nastran", "frequencies")))
    if len(sources) > 1:
        raise r.error(f"{path}.{sources[1]}", f"give one source of modal data; got "
                      f"{sources[0]} and {sources[1]}")
    source = {"file": "file", "nastran": "nastran"}.get(sources[0], "inline")
    fields: dict = {"source": source, "planar": not three_axis}
    if source == "file":
        fields["path"] = _data_path(r, r.take(t, "file", path)[0], f"{path}.file", (".toml",))
    elif source == "nastran":
        fields["path"] = _data_path(r, r.take(t, "nastran", path)[0], f"{path}.nastran",
                                    (".op2", ".npz"))
        fields["root"] = r.integer(t, "root", path, minimum=1)
        units, full = r.take(t, "units", path)
        if (not isinstance(units, (list, tuple)) or len(units) != 2
                or not all(isinstance(u, str) for u in units)):
            raise r.error(full, "must be [length unit, mass unit] of the finite-element model "
                          "(NASTRAN has none), e.g. [\"m\", \"kg\"], [\"mm\", \"t\"], "
                          f"[\"in\", \"slinch\"]; got {value_kind(units)}")
        for unit, table, what in zip(units, (LENGTH_UNITS, MASS_UNITS), ("length", "mass")):
            if unit not in table:
                raise r.error(full, f"the {what} unit must be one of {quoted_choices(table)}; got "
                              f"{shown_value(unit)}" + suggestion(unit, table))
        fields["units"] = tuple(units)
        if "mass_matrix" in t:
            fields["mass_matrix"] = _data_path(r, t.pop("mass_matrix"), f"{path}.mass_matrix",
                                               (".npy", ".npz"))
        fields["tip_grid"] = r.integer(t, "tip_grid", path, minimum=1, default=None)
        fields["subcase"] = r.integer(t, "subcase", path, minimum=1, default=None)
        axes = _matrix(r, t, "axes", path, "modal.axes", rows=3, columns=(3,))
        if axes is not None:
            fields["axes"] = axes
    else:
        if "frequencies_hz" in t:
            hz = r.vector(t, "frequencies_hz", path, "modal.frequencies_hz", limit="modes")
            fields["frequencies"] = tuple(2.0 * math.pi * f for f in hz)
        else:
            fields["frequencies"] = r.vector(t, "frequencies", path, "modal.frequencies",
                                             limit="modes")
        n = len(fields["frequencies"])
        width = (6,) if three_axis else (2, 6)
        fields["participation"] = _matrix(r, t, "participation", path, "modal.participation",
                                          rows=n, columns=width)
        fields["rigid_mass"] = _matrix(r, t, "rigid_mass", path, "modal.rigid_mass",
                                       columns=width)
        for key in ("participation", "rigid_mass"):
            if fields[key] is None:
                raise r.error(f"{path}.{key}", "missing required value")
        k = len(fields["participation"][0])
        if len(fields["rigid_mass"]) != k or len(fields["rigid_mass"][0]) != k:
            raise r.error(f"{path}.rigid_mass", f"must be {k}x{k} [kg, kg m, kg m^2] (one row "
                          f"and column per root motion of participation); got "
                          f"{len(fields['rigid_mass'])}x{len(fields['rigid_mass'][0])}")
        if "tip_motion" in t:
            if k == 2:
                fields["tip_motion"] = r.vector(t, "tip_motion", path, "modal.tip_motion",
                                                size=n)
            else:
                fields["tip_motion"] = _matrix(r, t, "tip_motion", path, "modal.tip_motion",
                                               rows=n, columns=(3,))
    fields["n_modes_kept"] = r.integer(t, "n_modes", path, minimum=1, limit="modes",
                                       default=None)
    if "damping" in t:
        value = t["damping"]
        if isinstance(value, (list, tuple)):
            fields["damping"] = r.vector(t, "damping", path, "beam.damping_ratio",
                                         limit="modes")
            largest = max(fields["damping"])
        else:
            fields["damping"] = largest = _with_unit_hint(
                lambda: r.number(t, "damping", path, "beam.damping_ratio"), value,
                _percent_hint)
        r.warn(f"{path}.damping", damping_in_percent(largest))
    fields["length"] = r.number(t, "length", path, "beam.length", default=None)
    allowed = {*_MODAL_KEYS[source], "damping", "length", "n_modes"}
    for key in list(t):
        for other, keys in _MODAL_KEYS.items():
            if other != source and key in keys:
                raise r.error(f"{path}.{key}", f"does not apply to modal data from "
                              f"{_MODAL_ORIGINS[source]}; it takes "
                              + ", ".join(sorted(allowed)))
    r.done(t, path, allowed)
    spec = ModalSpec(**fields)
    try:
        with library_limits(r.limits):
            model = spec.build()
    except ImportError as exc:
        raise r.error(f"{path}.nastran", str(exc)) from None
    except (TypeError, ValueError, OSError, FlexsatError) as exc:
        where = {"file": f"{path}.file", "nastran": f"{path}.nastran"}.get(source, path)
        raise r.error(where, str(exc)) from None
    if three_axis and not model.three_axis:
        raise r.error(path, "a three-axis scene needs six-axis modal data (participation of "
                      "n x 6, a 6x6 rigid_mass: translations x, y, z then rotations); these "
                      "are planar (n x 2)")
    try:
        length = model.length
    except ValueError:
        raise r.error(f"{path}.length", "missing: the data do not give the appendage's length "
                      "[m] (its extent along x from the root), which mounting it and fitting a "
                      "chain need") from None
    w = model.frequencies
    lo, hi = RANGES["modal.frequencies"].lo, RANGES["modal.frequencies"].hi
    if not (lo <= w[0] and w[-1] <= hi):
        raise r.error(path, f"cantilever frequencies from {w[0]:.4g} to {w[-1]:.4g} rad/s: "
                      f"outside [{lo:g}, {hi:g}] rad/s, the range flexsat's models are verified "
                      "for; check the data's units")
    if not 1e-2 <= length <= 1e3:
        raise r.error(f"{path}.length", f"the appendage's length {length:.4g} m lies outside "
                      "[0.01, 1000] m (beam.length's range); check the data's units")
    return _with_facts(spec, model)


def _with_facts(spec: ModalSpec, model) -> ModalSpec:
    """The spec with the data's facts for the report (fields that take no part in equality)."""
    w = model.frequencies
    return dataclasses.replace(spec, n_modes=int(w.size), first_frequency=float(w[0]),
                               last_frequency=float(w[-1]), mass=float(model.mass),
                               has_tip_motion=bool(model.has_tip_motion),
                               damping_range=(float(np.min(model.damping_ratios)),
                                              float(np.max(model.damping_ratios))))


def _structure_name(spec) -> str:
    """What an appendage's structure is, for messages."""
    if isinstance(spec, BeamSpec):
        return "a beam with a tip body" if spec.tip is not None else "a uniform beam"
    if isinstance(spec, SteppedBeamSpec):
        return "a stepped beam"
    if isinstance(spec, ModalSpec):
        return "given by modal data"
    return "a tapered beam"


def _read_stepped(r: SceneReader, data, path: str, tip: TipSpec | None) -> SteppedBeamSpec:
    """``appendages[i].stepped_beam``: ``segments`` (beam tables from the root outward) and
    one ``damping_ratio``."""
    t = r.table(data, path)
    damping = _read_damping_ratio(r, t, path)
    items, full = r.take(t, "segments", path)
    if not isinstance(items, (list, tuple)) or not items:
        raise r.error(full, "must be a non-empty array of tables, one per segment from the root "
                      f"outward ([[{path.split('[')[0]}.stepped_beam.segments]]); got "
                      f"{value_kind(items)}")
    r.check_limit(full, len(items), "bodies", f"{len(items)} segments")
    segments = tuple(_read_beam(r, item, f"{full}[{k}]", segment=True, damping=damping)
                     for k, item in enumerate(items))
    r.done(t, path, {"segments", "damping_ratio"})
    spec = SteppedBeamSpec(segments, damping, tip)
    _check_built_frequency(r, path, spec)
    return spec


def _read_tapered(r: SceneReader, data, path: str, tip: TipSpec | None) -> TaperedBeamSpec:
    """``appendages[i].tapered_beam``: a section whose dimensions vary linearly from
    ``root_dimensions`` to ``tip_dimensions``, as ``n_segments`` uniform segments."""
    t = r.table(data, path)
    section = r.choice(t, "section", path, tuple(TAPERED_SECTIONS))
    length = r.number(t, "length", path, "beam.length")
    n_segments = r.integer(t, "n_segments", path, minimum=1, limit="bodies",
                           default=TAPERED_SEGMENTS)
    ends = []
    for key in ("root_dimensions", "tip_dimensions"):
        p = f"{path}.{key}"
        dt = r.table(r.take(t, key, path)[0], p)
        dims = {name: r.number(dt, name, p, _SECTION_RANGES[name])
                for name in _SECTION_KEYS[section]}
        r.done(dt, p, set(_SECTION_KEYS[section]))
        _check_section_shape(r, p, section, length, dims)
        ends.append(tuple(dims.items()))
    density = r.number(t, "density", path, "beam.density")
    youngs = _with_unit_hint(lambda: r.number(t, "youngs_modulus", path, "beam.youngs_modulus"),
                             t.get("youngs_modulus"), _modulus_hint)
    r.warn(f"{path}.youngs_modulus", modulus_in_megapascals(youngs, density))
    poisson = r.number(t, "poisson_ratio", path, "beam.poisson_ratio", default=0.3)
    damping = _read_damping_ratio(r, t, path)
    r.done(t, path, {"section", "length", "n_segments", "root_dimensions", "tip_dimensions",
                     "density", "youngs_modulus", "poisson_ratio", "damping_ratio"})
    spec = TaperedBeamSpec(section, length, n_segments, ends[0], ends[1], density, youngs,
                           damping, poisson, tip)
    _check_built_frequency(r, path, spec)
    return spec


def _check_built_frequency(r: SceneReader, path: str, spec) -> None:
    """Build a stepped or tapered beam (refusals of the library by key) and check its first
    free-free bending frequency."""
    try:
        with library_limits(r.limits):
            structure = spec.build()
            omega_1 = float(structure.natural_frequencies(1)[0])
    except (TypeError, ValueError, FlexsatError) as exc:
        raise r.error(path, str(exc)) from None
    _check_first_frequency(r, path, omega_1, "of the assembled segments")


def _with_unit_hint(read, value, hint):
    """``read()``, its SceneError completed by ``hint(value)`` (the likely unit slip of a value
    outside the range) when there is one."""
    try:
        return read()
    except SceneError as exc:
        said = hint(value) if isinstance(value, (int, float)) and not isinstance(value, bool) \
            else None
        if said is None:
            raise
        raise SceneError(f"{exc}; {said}") from None


def _modulus_hint(value: float) -> str | None:
    """Below 1e5 Pa: the modulus in MPa or GPa gives a structural material (1e8-1e12 Pa)."""
    for factor, unit in ((1e6, "MPa"), (1e9, "GPa")):
        if 0 < value < 1e5 and 1e8 <= value * factor <= 1e12:
            return f"did you give {unit}? {value:g} {unit} = {value * factor:g} Pa"
    return None


def _percent_hint(value: float) -> str | None:
    """1 to 100: a damping ratio in per cent."""
    return (f"did you give per cent? {value:g} % = {value / 100:g}" if 1 <= value <= 100
            else None)


_CHAIN_ARRAYS = {"lengths": "chain.lengths", "masses": "chain.masses",
                 "inertias": "chain.inertias", "hinge_stiffnesses": "chain.hinge_stiffnesses",
                 "hinge_dampings": "chain.hinge_dampings", "com_offsets": "chain.com_offsets"}

#: An explicit chain's three-axis arrays (key -> range kind), :class:`appendages.HingedChain`'s
#: names: per body (inertias about local y, about the axis) or per joint.
_CHAIN_ARRAYS_3 = {"inertias_y": "chain.inertias", "torsional_inertias": "chain.torsional_inertias",
                   "hinge_stiffnesses_y": "chain.hinge_stiffnesses",
                   "hinge_dampings_y": "chain.hinge_dampings",
                   "torsion_stiffnesses": "chain.hinge_stiffnesses",
                   "torsion_dampings": "chain.hinge_dampings",
                   "axial_stiffnesses": "chain.axial_stiffnesses",
                   "axial_dampings": "chain.axial_dampings"}
_PER_BODY_3 = ("inertias_y", "torsional_inertias")


def _read_chain(r: SceneReader, data, path: str, has_beam: bool) -> ChainSpec:
    t = r.table(data, path)
    root = r.choice(t, "root", path, ("rigid", "hinged"), default="rigid")
    if "from_beam" in t:
        from_beam = r.choice(t, "from_beam", path, ("rfem",))
        if not has_beam:
            raise r.error(f"{path}.from_beam", "'rfem' (rigid finite elements of a beam) "
                          "needs a beam, stepped_beam or tapered_beam table in the same "
                          "appendage (modal data get a fitted chain: design = 'fit')")
        n_bodies = r.integer(t, "n_bodies", path, minimum=2, limit="bodies")
        root_stiffness = None
        root_damping = 0.0
        if root == "hinged":
            root_stiffness = r.number(t, "root_stiffness", path, "chain.root_stiffness")
            root_damping = r.number(t, "root_damping", path, "chain.root_damping", default=0.0)
        r.done(t, path, {"root", "from_beam", "n_bodies"}
               | ({"root_stiffness", "root_damping"} if root == "hinged" else set()))
        return ChainSpec(root=root, from_beam=from_beam, n_bodies=n_bodies,
                         root_stiffness=root_stiffness, root_damping=root_damping)
    three_axis = getattr(r, "three_axis", False)
    if not three_axis:
        for key in _CHAIN_ARRAYS_3:
            if key in t:
                raise r.error(f"{path}.{key}", "is a three-axis chain's key (x-z bending, "
                              "torsion, axial motion); a planar scene's chain bends in the x-y "
                              "plane only (inertias, hinge_stiffnesses, hinge_dampings)")
    values = {}
    for key in ("lengths", "masses", "inertias", "hinge_stiffnesses"):
        values[key] = r.vector(t, key, path, _CHAIN_ARRAYS[key], limit="bodies")
    for key in ("hinge_dampings", "com_offsets"):
        values[key] = r.vector(t, key, path, _CHAIN_ARRAYS[key], default=None, limit="bodies")
    if three_axis:
        values["torsional_inertias"] = r.vector(t, "torsional_inertias", path,
                                                _CHAIN_ARRAYS_3["torsional_inertias"],
                                                limit="bodies")
        for key, kind in _CHAIN_ARRAYS_3.items():
            if key != "torsional_inertias":
                values[key] = r.vector(t, key, path, kind, default=None, limit="bodies")
        for damping, spring in (("torsion_dampings", "torsion_stiffnesses"),
                                ("axial_dampings", "axial_stiffnesses")):
            if values[damping] is not None and values[spring] is None:
                raise r.error(f"{path}.{damping}", f"needs the springs it damps: give "
                              f"{path}.{spring} too")
    n = len(values["lengths"])
    n_hinges = n - 1 if root == "rigid" else n
    if n_hinges < 1:
        raise r.error(f"{path}.lengths", "must have at least 2 entries (bodies) for root = "
                      "'rigid', or 1 with root = 'hinged'")
    per_body = ("masses", "inertias", "com_offsets", *_PER_BODY_3)
    for key, value in values.items():
        if key == "lengths" or value is None:
            continue
        size = n if key in per_body else n_hinges
        if len(value) != size:
            what = "body" if key in per_body else f"hinge (root = {root!r})"
            raise r.error(f"{path}.{key}", f"must have {size} entries, one per {what}; got "
                          f"{len(value)}")
    if values["com_offsets"] is not None:
        for k, (offset, length) in enumerate(zip(values["com_offsets"], values["lengths"])):
            if offset > length:
                raise r.error(f"{path}.com_offsets[{k}]", f"must lie on the body, at most its "
                              f"length {length:g} [m]; got {offset:g}")
    r.done(t, path, {"root", *_CHAIN_ARRAYS, "from_beam"}
           | (set(_CHAIN_ARRAYS_3) if three_axis else set()))
    return ChainSpec(root=root, **values)


def _read_appendage(r: SceneReader, data, path: str, index: int) -> AppendageSpec:
    t = r.table(data, path)
    name, full = r.take(t, "name", path, f"appendage{index + 1}")
    if not isinstance(name, str) or not NAME_PATTERN.fullmatch(name) or len(name) > NAME_LENGTH:
        raise r.error(full, f"must be an ASCII identifier of at most {NAME_LENGTH} characters "
                      "(a letter or '_', then letters, digits or '_': it names FMU variables); "
                      f"got {value_kind(name)}")
    three_axis = getattr(r, "three_axis", False)
    orientation = None
    if three_axis:
        position = r.vector(t, "position", path, "position", default=(0.0, 0.0, 0.0), size=3)
        orientation = _read_orientation(r, t, path)
    else:
        for key in ("orientation", "orientation_sequence"):
            if key in t:
                raise r.error(f"{path}.{key}", "applies to three-axis scenes only (hub.inertia "
                              "a 3x3 tensor [kg m^2]); a planar appendage has a direction")
        position = r.vector(t, "position", path, "position", default=(0.0, 0.0), size=2)
    if three_axis and "direction" in t:
        raise r.error(f"{path}.direction", "is planar; a three-axis appendage has an "
                      "orientation (Euler angles [deg] in orientation_sequence, default 'ZYX')")
    direction_value, full = r.take(t, "direction", path, 0.0)
    if isinstance(direction_value, (list, tuple)):
        vec = r.vector({"direction": direction_value}, "direction", path, "direction vector",
                       size=2)
        if vec[0] == 0 and vec[1] == 0:
            raise r.error(full, "must be a non-zero vector")
        direction = math.atan2(vec[1], vec[0])
    else:
        degrees = r.check_number(direction_value, full, "direction")
        r.warn(full, radians_in_degrees(degrees))
        direction = math.radians(degrees)
    given = [key for key in STRUCTURES if key in t]
    if len(given) > 1:
        raise r.error(f"{path}.{given[1]}", f"an appendage is one structure: give one of "
                      f"{', '.join(STRUCTURES)}; got {given[0]} and {given[1]}")
    tip = _read_tip(r, t.pop("tip"), f"{path}.tip") if "tip" in t else None
    if tip is not None and not set(given) & {"beam", "stepped_beam", "tapered_beam"}:
        raise r.error(f"{path}.tip", "a tip body sits at the free end of a beam (a beam, "
                      "stepped_beam or tapered_beam table)" + (
                          "; modal data carry their tip body in the finite-element model"
                          if "modal" in given else ""))
    beam = modal = None
    if "modal" in t:
        modal = _read_modal(r, t.pop("modal"), f"{path}.modal")
    elif "beam" in t:
        beam = _read_beam(r, t.pop("beam"), f"{path}.beam", tip=tip)
    elif "stepped_beam" in t:
        beam = _read_stepped(r, t.pop("stepped_beam"), f"{path}.stepped_beam", tip)
    elif "tapered_beam" in t:
        beam = _read_tapered(r, t.pop("tapered_beam"), f"{path}.tapered_beam", tip)
    structure = beam if beam is not None else modal
    if three_axis:
        _check_three_axis_appendage(r, t, path, structure)
    distributed = beam is not None  # rfem divides any beam: uniform, tip-loaded, stepped
    chain = (_read_chain(r, t.pop("chain"), f"{path}.chain", distributed)
             if "chain" in t else None)
    truth_chain = (_read_chain(r, t.pop("truth_chain"), f"{path}.truth_chain", distributed)
                   if "truth_chain" in t else None)
    if structure is None and chain is None:
        raise r.error(path, "needs a structure (a beam, stepped_beam, tapered_beam or modal "
                      "table) or a chain table (or both)")
    truth = r.choice(t, "truth", path, ("beam", "modal", "chain"),
                     default="beam" if beam is not None else
                     ("modal" if modal is not None else "chain"))
    if truth == "beam" and beam is None:
        raise r.error(f"{path}.truth", "is 'beam' but the appendage has no beam table (beam, "
                      "stepped_beam or tapered_beam)" + ("; its modal data are truth = 'modal'"
                                                         if modal is not None else ""))
    if truth == "modal" and modal is None:
        raise r.error(f"{path}.truth", "is 'modal' but the appendage has no modal table")
    if truth == "chain" and chain is None and truth_chain is None:
        raise r.error(f"{path}.truth", "is 'chain' but the appendage has no chain table")
    if truth_chain is not None and truth != "chain":
        raise r.error(f"{path}.truth_chain", "applies to truth = 'chain' only")
    design = r.choice(t, "design", path, ("fit", "chain", "truth"),
                      default="fit" if structure is not None and truth != "chain" else
                      ("chain" if chain is not None else "truth"))
    fit = None
    if design == "fit":
        if structure is None:
            raise r.error(f"{path}.design", "is 'fit' but there is no structure to fit (a beam, "
                          "stepped_beam, tapered_beam or modal table)")
        ft = r.table(t.pop("fit", {}), f"{path}.fit")
        n_bodies = r.integer(ft, "n_bodies", f"{path}.fit", minimum=2, limit="fit_bodies",
                             default=3)
        # the paper's frequency fit is a symmetric chain of frozen pieces of a uniform rod
        paper = structure.uniform
        match = r.choices(ft, "match", f"{path}.fit", MATCHES,
                          default=list(MATCHES) if paper else ["poles-and-zeros"])
        if not match:
            raise r.error(f"{path}.fit.match", "must name at least one criterion")
        if "frequencies" in match and not paper:
            raise r.error(f"{path}.fit.match", "'frequencies' (the paper's fit: a symmetric "
                          "chain of frozen pieces of a uniform rod) needs a uniform beam "
                          f"without a tip body; this appendage is {_structure_name(structure)}: "
                          "use 'poles-and-zeros' (flexsat's fit, any appendage)")
        r.done(ft, f"{path}.fit", {"n_bodies", "match"})
        fit = FitSpec(n_bodies, match)
    elif "fit" in t:
        raise r.error(f"{path}.fit", f"applies to design = 'fit' only; design is {design!r}")
    if design == "chain" and chain is None:
        raise r.error(f"{path}.design", "is 'chain' but the appendage has no chain table")
    r.done(t, path, {"name", "position", "direction", *STRUCTURES, "tip", "chain",
                     "truth_chain", "truth", "design", "fit"}
           | ({"orientation", "orientation_sequence"} if three_axis else set()))
    return AppendageSpec(name, position, direction, truth, design, beam, chain, fit, truth_chain,
                         orientation, modal)


def _read_inertia_tensor(r: SceneReader, value, full: str, *, kind: str = "hub.inertia tensor",
                         about: str = "about the hub's centre of mass, hub axes") -> tuple:
    """A 3x3 inertia tensor of a body [kg m^2], rows as tuples: the hub's symmetric positive
    definite (the checks of :class:`~spacecraft.dynamics.hub.Hub`), a tip body's positive
    semi-definite (:func:`appendages.tip.check_inertia_tensor`; ``kind`` its range)."""
    import numpy as np

    from appendages.tip import check_inertia_tensor

    from ..dynamics.hub import Hub

    if len(value) != 3 or not all(isinstance(row, (list, tuple)) and len(row) == 3
                                  for row in value):
        raise r.error(full, f"must be a number (planar) or a 3x3 array of numbers [kg m^2] "
                      f"(three axes: the tensor {about})")
    rows = tuple(tuple(r.check_number(v, f"{full}[{i}][{j}]", kind)
                       for j, v in enumerate(row)) for i, row in enumerate(value))
    try:
        if kind == "hub.inertia tensor":
            Hub(1.0, np.array(rows))
        else:
            check_inertia_tensor("inertia", rows)
    except ValueError as exc:
        message = str(exc)
        for name in ("hub inertia ", "inertia "):  # the name the check was given leads
            if message.startswith(name):
                message = message[len(name):]
                break
        raise r.error(full, message) from None
    return rows


def _read_orientation(r: SceneReader, t: dict, path: str) -> tuple:
    """``orientation``: Euler angles [deg] of the appendage's axes (local x along it) in the
    ``orientation_sequence`` (default ``"ZYX"``: yaw about the hub's z, then pitch about the
    new y, then roll about the new x, the appendage's own axis)."""
    from ..dynamics.kinematics import euler_orientation

    angles = r.vector(t, "orientation", path, "orientation", default=(0.0, 0.0, 0.0), size=3)
    for k, angle in enumerate(angles):
        r.warn(f"{path}.orientation[{k}]", radians_in_degrees(angle))
    sequence, full = r.take(t, "orientation_sequence", path, "ZYX")
    try:
        R = euler_orientation(sequence, [math.radians(a) for a in angles])
    except (TypeError, ValueError) as exc:
        raise r.error(full, str(exc)) from None
    return tuple(tuple(float(v) for v in row) for row in R)


def _check_three_axis_appendage(r: SceneReader, t: dict, path: str, beam) -> None:
    """A three-axis scene needs beams that twist and stretch (sections give GJ, rho I_p, EA) and
    fitted design chains (3-D chains in every motion)."""
    sections = []
    if isinstance(beam, BeamSpec):
        sections = [(f"{path}.beam.section", beam.section)]
    elif isinstance(beam, SteppedBeamSpec):
        sections = [(f"{path}.stepped_beam.segments[{k}].section", segment.section)
                    for k, segment in enumerate(beam.segments)]
    for key, section in sections:
        if section == "uniform":
            raise r.error(key, "a three-axis scene needs the torsional and axial properties "
                          "that a section gives (GJ [N m^2] with Poisson's ratio, rho*I_p "
                          "[kg m], EA [N]): 'rod', 'tube' or 'rectangular'; got 'uniform' "
                          "(bending only)")
    for key in ("chain", "truth_chain"):
        chain = t.get(key)
        if not isinstance(chain, Mapping):
            continue
        if chain.get("root", "rigid") == "hinged" and "from_beam" in chain:
            raise r.error(f"{path}.{key}.root", "'hinged' with from_beam = 'rfem' is planar "
                          "(one drive spring, root_stiffness [N m/rad], about the bending "
                          "axis); a three-axis chain with a hinged root gives its arrays, "
                          "every per-joint array with a first entry for the joint between "
                          "mount and body 1")
    explicit = any(isinstance(t.get(key), Mapping) and "from_beam" not in t[key]
                   for key in ("chain", "truth_chain"))
    if beam is None and not explicit:
        raise r.error(path, "a three-axis appendage needs a structure (a beam, stepped_beam, "
                      "tapered_beam or modal table) or an explicit chain (its arrays)")


def _read_controller(r: SceneReader, data, path: str) -> ControllerSpec:
    t = r.table(data, path)
    # unknown keys first: a misspelt table ([controller.pid]) is named as such, not taken for
    # a missing [controller.pd]
    own = ("types", "sample_rate", "given", "delay", "computation_delay", *CONTROLLERS)
    r.done({k: v for k, v in t.items() if k not in own}, path, set(own))
    present = tuple(c for c in CONTROLLERS if c in t)
    types = r.choices(t, "types", path, CONTROLLERS, default=list(present or ("pd",)))
    if not types:
        raise r.error(f"{path}.types", "must name at least one controller")
    rate = r.number(t, "sample_rate", path, "controller.sample_rate", default=None)
    delay, computation_delay = read_delay(r, t, path, None if rate is None else 1.0 / rate)
    pd_spec = lqr_spec = None
    if "pd" in types:
        p = f"{path}.pd"
        pt = r.table(t.pop("pd", {}), p)
        wn = r.number(pt, "natural_frequency", p, "pd.frequency", default=None)
        wb = r.number(pt, "bandwidth", p, "pd.frequency", default=None)
        if (wn is None) == (wb is None):
            raise r.error(p, "give exactly one of natural_frequency [rad/s] or bandwidth [rad/s]")
        damping = r.number(pt, "damping", p, "pd.damping", default=0.7)
        roll_off = r.number(pt, "roll_off", p, "pd.filter", default=None)
        notch_value, full = r.take(pt, "notch", p, None)
        if notch_value is not None and notch_value != "first_mode":
            notch_value = r.check_number(notch_value, full, "pd.filter")
        r.done(pt, p, {"natural_frequency", "bandwidth", "damping", "roll_off", "notch"})
        pd_spec = PDSpec(wn, wb, damping, roll_off, notch_value)
    elif "pd" in t:
        raise r.error(f"{path}.pd", "is given but 'pd' is not in controller.types")
    if "lqr" in types:
        p = f"{path}.lqr"
        if "lqr" not in t:
            raise r.error(p, "missing: controller.types lists 'lqr' but there are no weights")
        lt = r.table(t.pop("lqr"), p)
        lqr_spec = LQRSpec(
            attitude_weight=r.number(lt, "attitude_weight", p, "lqr.attitude_weight"),
            torque_weight=r.number(lt, "torque_weight", p, "lqr.torque_weight"),
            rate_weight=r.number(lt, "rate_weight", p, "lqr.rate_weight", default=0.0),
            deflection_weight=r.number(lt, "deflection_weight", p, "lqr.deflection_weight",
                                       default=None),
            estimator_speed=r.number(lt, "estimator_speed", p, "lqr.estimator_speed",
                                     default=3.0))
        r.done(lt, p, {"attitude_weight", "torque_weight", "rate_weight", "deflection_weight",
                       "estimator_speed"})
    elif "lqr" in t:
        raise r.error(f"{path}.lqr", "is given but 'lqr' is not in controller.types")
    given = None
    if "given" in t:
        given = read_given(t.pop("given"), f"{path}.given", types, r.error,
                           three_axis=getattr(r, "three_axis", False), max_states=r.limits.states)
    r.done(t, path, {"types", "sample_rate", "pd", "lqr"})
    return ControllerSpec(types, pd_spec, lqr_spec, None if rate is None else 1.0 / rate, given,
                          delay, computation_delay)


def _read_manoeuvre(r: SceneReader, data, path: str, names, sample_time,
                    delay: float = 0.0) -> ManoeuvreSpec:
    t = r.table(data, path)
    degrees = r.number(t, "slew_angle", path, "manoeuvre.slew_angle")
    r.warn(f"{path}.slew_angle", radians_in_degrees(degrees))
    angle = math.radians(degrees)
    slew_time = r.number(t, "slew_time", path, "manoeuvre.slew_time")
    duration = r.number(t, "duration", path, "manoeuvre.duration", default=None)
    duration = 3.0 * slew_time if duration is None else duration
    default_step = sample_time if sample_time is not None else slew_time / 500.0
    if sample_time is None and delay > 0:
        # a continuous controller's delayed loop is simulated with the command held every step:
        # at most 2 x delay (controllers.delay)
        default_step = min(default_step, 2.0 * delay)
    step = r.number(t, "step", path, "manoeuvre.step", default=None)
    if step is not None and sample_time is None and step > 2.0 * delay * (1 + 1e-12) > 0:
        raise r.error(f"{path}.step", f"must be at most 2 x controller.delay = {2 * delay:g} s "
                      "for a continuous controller with a delay (its delayed loop is simulated "
                      f"with the command held every step, controllers.delay); got {step:g}: "
                      "shorten it or remove it (the default then fits)")
    step = default_step if step is None else step
    if sample_time is not None and not math.isclose(step, sample_time, rel_tol=1e-9):
        raise r.error(f"{path}.step", f"must equal the controller's sample time "
                      f"1/sample_rate = {sample_time:g} s for a digital controller (a sampled "
                      f"loop is simulated at its samples); got {step:g}: remove manoeuvre.step "
                      "(it defaults to the sample time) or change controller.sample_rate")
    if duration < 2 * step:
        raise r.error(f"{path}.duration", f"must cover at least two steps ({2 * step:g} s); "
                      f"got {duration:g}")
    disturbance = None
    if "disturbance" in t:
        p = f"{path}.disturbance"
        dt_ = r.table(t.pop("disturbance"), p)
        three_axis = getattr(r, "three_axis", False)
        if three_axis:
            inputs = ("disturbance_torque", "force",
                      *(f"{q}_{a}" for q in ("disturbance_torque", "force") for a in "xyz"),
                      *(f"{n}_tip_force_{a}" for n in names for a in "yz"))
        else:
            inputs = ("disturbance_torque", "force_x", "force_y",
                      *(f"{n}_tip_force" for n in names))
        disturbance = DisturbanceSpec(
            input=r.choice(dt_, "input", p, inputs),
            amplitude=r.number(dt_, "amplitude", p, "disturbance.amplitude"),
            start=r.number(dt_, "start", p, "disturbance.start", default=0.0),
            length=r.number(dt_, "length", p, "disturbance.length", default=None))
        axis = None
        if three_axis and disturbance.input in ("disturbance_torque", "force"):
            axis = _read_axis(r, dt_, p, "axis", "disturbance.axis")
        elif "axis" in dt_:
            raise r.error(f"{p}.axis", "applies to a three-axis scene's 'disturbance_torque' "
                          "or 'force' (their direction in hub axes); "
                          + ("this input names its own direction" if three_axis else
                             "a planar disturbance acts in the hub's plane"))
        disturbance = dataclasses.replace(disturbance, axis=axis)
        r.done(dt_, p, {"input", "amplitude", "start", "length", "axis"})
        if disturbance.start >= duration:
            raise r.error(f"{p}.start", f"must fall inside the simulated time, before "
                          f"manoeuvre.duration = {duration:g} [s]; got {disturbance.start:g}")
    slew_axis = None
    if getattr(r, "three_axis", False):
        slew_axis = _read_slew_axis(r, t, path)
    elif "slew_axis" in t:
        raise r.error(f"{path}.slew_axis", "applies to three-axis scenes only (hub.inertia a "
                      "3x3 tensor [kg m^2]); a planar slew turns about the hub's z axis")
    flown = read_profile(r, t, path)
    r.done(t, path, {"slew_angle", "slew_time", "duration", "step", "disturbance", "slew_axis",
                     *MANOEUVRE_KEYS})
    return ManoeuvreSpec(angle, slew_time, duration, step, disturbance, slew_axis, **flown)


def _read_slew_axis(r: SceneReader, t: dict, path: str) -> tuple:
    """``slew_axis``: ``"x"``, ``"y"``, ``"z"`` or a non-zero 3-vector in hub axes
    (normalised here), the axis of the eigen-axis slew."""
    return _read_axis(r, t, path, "slew_axis", "manoeuvre.slew_axis")


def _read_axis(r: SceneReader, t: dict, path: str, key: str, kind: str) -> tuple:
    """A direction in hub axes: ``"x"``, ``"y"``, ``"z"`` or a non-zero 3-vector (range
    ``kind``), normalised."""
    value, full = r.take(t, key, path)
    if isinstance(value, str):
        if value not in ("x", "y", "z"):
            raise r.error(full, f"must be 'x', 'y', 'z' or an array of 3 numbers (hub axes); "
                          f"got {shown_value(value)}")
        return tuple(float(a == value) for a in "xyz")
    axis = r.vector({key: value}, key, path, kind, size=3)
    largest = max(abs(a) for a in axis)
    if largest == 0.0:
        raise r.error(full, "must be a non-zero vector (hub axes); got [0, 0, 0]")
    # scaled by the largest entry first: [1e-300, 0, 0] is the x axis, not a zero vector
    # (its squares would underflow)
    scaled = [a / largest for a in axis]
    norm = math.sqrt(sum(a * a for a in scaled))
    return tuple(a / norm for a in scaled)


def _read_simulator(r: SceneReader, data, path: str) -> SimulatorSpec:
    t = r.table(data, path)
    name = r.choice(t, "name", path, SIMULATORS, default="flexsat")
    rate = r.number(t, "sample_rate", path, "simulator.sample_rate", default=None)
    dt = r.number(t, "dt", path, "simulator.dt", default=None)
    wheel = None
    if "reaction_wheel" in t:
        p = f"{path}.reaction_wheel"
        wt = r.table(t.pop("reaction_wheel"), p)
        wheel = ReactionWheelSpec(
            spin_inertia=r.number(wt, "spin_inertia", p, "reaction_wheel.spin_inertia"),
            max_torque=r.number(wt, "max_torque", p, "reaction_wheel.max_torque", default=None),
            max_speed=r.number(wt, "max_speed", p, "reaction_wheel.max_speed", default=None))
        r.done(wt, p, {"spin_inertia", "max_torque", "max_speed"})
    r.done(t, path, {"name", "sample_rate", "dt", "reaction_wheel"})
    if name != "basilisk" and (rate is not None or dt is not None or wheel is not None):
        raise r.error(path, "sample_rate, dt and reaction_wheel apply to name = 'basilisk' only")
    sample_time = None if rate is None else 1.0 / rate
    if dt is not None and sample_time is not None and dt > sample_time * (1 + 1e-12):
        raise r.error(f"{path}.dt", f"must not exceed the flight-software sample time "
                      f"1/sample_rate = {sample_time:g} [s]; got {dt:g}")
    if dt is not None and sample_time is not None:
        # Basilisk's clock counts whole nanoseconds: dt must divide T in them (the RK4 step
        # against the chain's modes is checked when the run is built)
        period, k = round(sample_time * 1e9), round(sample_time / dt)
        if k < 1 or period % k or abs(k * dt - sample_time) > 1e-9 * sample_time:
            raise r.error(f"{path}.dt", f"must divide the flight-software sample time "
                          f"1/sample_rate = {sample_time:g} s into a whole number of "
                          f"whole-nanosecond steps [s]; got {dt:g} (T / dt = "
                          f"{sample_time / dt:.6g})")
    return SimulatorSpec(name, sample_time, dt, wheel)


def _limit_value(r: SceneReader, value, full: str, name: str):
    """A limit: a positive integer (``memory``, ``basilisk_seconds``: a positive number)."""
    unit = LIMIT_UNITS[name][0]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise r.error(full, f"must be a positive number [{unit}]; got {value_kind(value)}")
    try:
        number = float(value)
    except (OverflowError, ValueError):
        raise r.error(full, f"must be finite [{unit}]; got {shown_value(value)}") from None
    if not (math.isfinite(number) and number >= 1):
        raise r.error(full, f"must be a finite number >= 1 [{unit}]; got {shown_value(value)}")
    if name in REAL_LIMITS:
        return number
    if number != math.floor(number):
        raise r.error(full, f"must be a whole number [{unit}]; got {shown_value(value)}")
    return int(number)


def read_limits(data: Mapping, source: str = "") -> dict:
    """Check a mapping of limit overrides (a scene's ``[limits]`` table, ``--limit`` options).

    Returns
    -------
    dict
        ``name -> value`` (int, or float bytes for ``memory``), for :class:`Limits`.

    Raises
    ------
    SceneError
        An unknown limit or a value that is not a positive whole number.
    """
    r = SceneReader(source)
    t = r.table(data, "limits")
    values = {name: _limit_value(r, t.pop(name), f"limits.{name}", name)
              for name in Limits.names() if name in t}
    r.done(t, "limits", Limits.names())
    return values


def _check_cost(r: SceneReader, scene: Scene) -> None:
    """Refuse a scene whose estimated work exceeds the limits, naming the key to change."""
    cost = estimate_cost(scene)
    limits = r.limits
    m = scene.manoeuvre
    if cost.loop_states > limits.states:
        r.check_limit(cost.loop_key, cost.loop_states, "states",
                      f"the largest closed loop would have up to {cost.loop_states} states")
    if m is not None:
        if scene.controller.sample_time is None:
            r.check_limit("manoeuvre.step", cost.samples, "samples",
                          f"{cost.samples:.4g} samples per simulation (duration {m.duration:g} s"
                          f" / step {m.step:g} s)")
        else:
            r.check_limit("manoeuvre.step", cost.samples * DIGITAL_SAMPLE_COST, "samples",
                          f"{cost.samples:.4g} samples per simulation of a digital loop "
                          f"(duration {m.duration:g} s / step {m.step:g} s), each counting "
                          f"{DIGITAL_SAMPLE_COST}")
        if cost.memory > limits.memory:
            raise r.error("manoeuvre.step", f"the time responses would take up to "
                          f"{cost.memory / 2**30:.3g} GiB ({cost.simulations} simulations of "
                          f"{cost.samples} samples), over limits.memory = "
                          f"{limits.memory / 2**30:.3g} GiB; lengthen manoeuvre.step, shorten "
                          "manoeuvre.duration or ask for fewer controllers or fits; or raise "
                          "limits.memory [bytes] if you really want more")
    if scene.export.fmu and scene.export.reference_files:
        step = scene.export.step or m.step
        stop = m.duration if m is not None else 100.0 * step
        r.check_limit("export.step", int(stop / step + 1e-9) + 1, "samples",
                      f"{stop / step:.4g} samples of the FMU reference files (stop {stop:g} s "
                      f"/ step {step:g} s)")


#: The motions ``fidelity.modes_per_motion`` pins, by the kind of truncated beam: planar;
#: three-axis uniform (its motions separate); three-axis with modes ranked together (a tip
#: body, segments).
PINNED_MOTIONS = {"planar": ("bending",), "uniform": ("xy", "xz", "torsion", "axial"),
                  "coupled": ("coupled",)}


def _read_modes_per_motion(r: SceneReader, data, appendages, n_modes) -> tuple | None:
    """``fidelity.modes_per_motion`` (module table): None when not given; else per truncated
    beam the pinned modes, ``((appendage, ((motion, count), ...)), ...)``, sorted by name."""
    path = "fidelity.modes_per_motion"
    if data is None:
        return None
    t = r.table(data, path)
    if n_modes is None:
        raise r.error(path, "goes with fidelity.n_modes (it pins the modes a run from "
                      "fidelity.tolerance chooses for itself); give n_modes or leave it out")
    specs = {a.name: a for a in appendages}
    out = []
    for name in sorted(t, key=str):
        full = f"{path}.{name}"
        if name not in specs:
            raise r.error(full, "unknown appendage; expected one of "
                          + ", ".join(sorted(specs)) + suggestion(name, sorted(specs)))
        a = specs[name]
        if a.truth != "beam":
            raise r.error(full, f"pins modes of a truncated beam; appendage {name!r} has "
                          f"truth = {a.truth!r}, not 'beam'")
        kind = (("uniform" if a.beam.uniform else "coupled") if getattr(r, "three_axis", False)
                else "planar")
        allowed = PINNED_MOTIONS[kind]
        counts = r.table(t[name], full)
        if not counts:
            raise r.error(full, "must name at least one motion: " + ", ".join(allowed))
        pinned = []
        for motion in sorted(counts, key=str):
            key = f"{full}.{motion}"
            if motion not in allowed:
                what = {"planar": "a planar beam", "uniform": "a uniform three-axis beam",
                        "coupled": "a three-axis beam whose modes are ranked together (a tip "
                                   "body, segments)"}[kind]
                raise r.error(key, f"not a motion of {what}; expected one of "
                              + ", ".join(allowed) + suggestion(str(motion), list(allowed)))
            value = counts[motion]
            if (isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral)
                    or value < 1):
                raise r.error(key, f"must be an integer >= 1 [-]; got {shown_value(value)}")
            r.check_limit(key, int(value), "modes")
            pinned.append((str(motion), int(value)))
        out.append((str(name), tuple(pinned)))
    return tuple(out)


def _read_scene(data: Mapping, source: str, limit_overrides: Mapping | None = None,
                base: Path | None = None) -> Scene:
    r = SceneReader(source)
    r.base = base  # the folder of data files named relative to the scene
    t = r.table(data, "")
    # the limits first: they bound what the rest may ask for
    if isinstance(t.get("limits"), Mapping) and "file_size" in t["limits"]:
        raise r.error("limits.file_size", "bounds the scene file before it is read: give it "
                      "on the command line (--limit file_size=N [bytes])")
    limits = dict(read_limits(t.pop("limits", {}), source)) if "limits" in t else {}
    limits.update(limit_overrides or {})
    r.limits = Limits(**limits)
    title = r.text(t, "title", "", "")
    ht = r.table(r.take(t, "hub", "")[0], "hub")
    mass = r.number(ht, "mass", "hub", "hub.mass")
    if isinstance(ht.get("inertia"), (list, tuple)):
        hub = HubSpec(mass, _read_inertia_tensor(r, ht.pop("inertia"), "hub.inertia"))
    else:
        hub = HubSpec(mass, r.number(ht, "inertia", "hub", "hub.inertia"))
    r.done(ht, "hub", {"mass", "inertia"})
    r.three_axis = hub.three_axis
    items, full = r.take(t, "appendages", "")
    if not isinstance(items, (list, tuple)) or not items:
        raise r.error(full, "must be a non-empty array of tables ([[appendages]])")
    r.check_limit(full, len(items), "appendages", f"{len(items)} appendages")
    appendages = tuple(_read_appendage(r, item, f"appendages[{k}]", k)
                       for k, item in enumerate(items))
    seen: set = set()
    for k, a in enumerate(appendages):
        if a.name in seen:
            raise r.error(f"appendages[{k}].name", f"{a.name!r} is used twice")
        seen.add(a.name)

    ft = r.table(t.pop("fidelity", {}), "fidelity")
    n_modes = r.integer(ft, "n_modes", "fidelity", minimum=1, limit="modes", default=None)
    tolerance = r.number(ft, "tolerance", "fidelity", "fidelity.tolerance", default=None)
    if n_modes is not None and tolerance is not None:
        raise r.error("fidelity", "give n_modes or tolerance, not both")
    if n_modes is None and tolerance is None:
        tolerance = 1e-3
    pinned = _read_modes_per_motion(r, ft.pop("modes_per_motion", None), appendages, n_modes)
    fidelity = FidelitySpec(
        n_modes=n_modes, tolerance=tolerance, modes_per_motion=pinned,
        method=r.choice(ft, "method", "fidelity", METHODS, default="craig-bampton"),
        bandwidth_factor=r.number(ft, "bandwidth_factor", "fidelity",
                                  "fidelity.bandwidth_factor", default=5.0),
        prune=r.boolean(ft, "prune", "fidelity", True))
    r.done(ft, "fidelity", {"n_modes", "tolerance", "method", "bandwidth_factor", "prune",
                            "modes_per_motion"})

    controller = _read_controller(r, r.take(t, "controller", "")[0], "controller")
    manoeuvre = None
    if "manoeuvre" in t:
        manoeuvre = _read_manoeuvre(r, t.pop("manoeuvre"), "manoeuvre", [a.name for a in
                                                                           appendages],
                                    controller.sample_time, controller.delay)

    ot = r.table(t.pop("outputs", {}), "outputs")
    outputs = OutputsSpec(r.boolean(ot, "tip_deflection", "outputs", False),
                          r.boolean(ot, "root_loads", "outputs", False),
                          r.boolean(ot, "exact_reference", "outputs", False))
    r.done(ot, "outputs", {"tip_deflection", "root_loads", "exact_reference"})
    if pinned == () and not getattr(r, "three_axis", False):
        raise r.error("fidelity.modes_per_motion", "is empty, which pins nothing in a planar "
                      "scene: name a truncated beam's modes "
                      "(fidelity.modes_per_motion.<name>.bending)")

    et = r.table(t.pop("export", {}), "export")
    export = ExportSpec(fmu=r.boolean(et, "fmu", "export", False),
                        systems=r.choices(et, "systems", "export", EXPORTABLE,
                                          default=list(EXPORTABLE)),
                        reference_files=r.boolean(et, "reference_files", "export", True),
                        step=r.number(et, "step", "export", "export.step", default=None),
                        fmi_versions=r.choices(et, "fmi_version", "export", FMI_VERSIONS,
                                               default=["2.0"]),
                        sources_only=r.boolean(et, "sources_only", "export", False),
                        ssp=r.boolean(et, "ssp", "export", False))
    r.done(et, "export", {"fmu", "systems", "reference_files", "step", "fmi_version",
                          "sources_only", "ssp"})
    if not export.fmi_versions:
        raise r.error("export.fmi_version", f"must name at least one of {quoted_choices(FMI_VERSIONS)}")
    if export.ssp and not {"plant", "controller"} <= set(export.systems):
        raise r.error("export.ssp", "needs both 'plant' and 'controller' in export.systems (an "
                      "SSP connects the two FMUs)")

    rt = r.table(t.pop("report", {}), "report")
    plots_value, full = r.take(rt, "plots", "report", False)
    if isinstance(plots_value, bool):
        plots = PLOTS if plots_value else ()
    else:
        if isinstance(plots_value, (list, tuple)):
            plots_value = [PLOT_ALIASES.get(p, p) if isinstance(p, str) else p
                           for p in plots_value]
        elif isinstance(plots_value, str):
            plots_value = PLOT_ALIASES.get(plots_value, plots_value)
        plots = r.choices({"plots": plots_value}, "plots", "report", PLOTS, default=())
    equivalence = r.boolean(rt, "equivalence", "report", True)
    timeseries = r.boolean(rt, "timeseries", "report", True)
    r.done(rt, "report", {"plots", "equivalence", "timeseries"})
    simulator = (_read_simulator(r, t.pop("simulator"), "simulator") if "simulator" in t
                 else SimulatorSpec())
    wheels = (read_wheels(r, t.pop("wheels"), "wheels", hub.three_axis) if "wheels" in t
              else None)
    sensors = (read_sensors(r, t.pop("sensors"), "sensors", hub.three_axis,
                            controller.sample_time) if "sensors" in t else None)
    r.done(t, "", {"title", "hub", "appendages", "fidelity", "controller", "manoeuvre",
                   "outputs", "export", "report", "limits", "simulator", "wheels", "sensors"})

    # outputs the scene cannot produce
    if outputs.exact_reference and not any(a.truth in ("beam", "modal") for a in appendages):
        raise r.error("outputs.exact_reference", "needs an appendage whose truth has an exact "
                      "W (a distributed beam, truth = 'beam', or modal data, truth = 'modal'); "
                      "this scene has only chains")
    if fidelity.n_modes is None and not any(a.truth == "beam" for a in appendages):
        fidelity = dataclasses.replace(fidelity, tolerance=None, n_modes=None)
    if "slew" in plots and manoeuvre is None:
        raise r.error("report.plots", "asks for 'slew' but the scene has no manoeuvre table")
    if (controller.lqr is not None and controller.lqr.deflection_weight is not None
            and not outputs.tip_deflection):
        raise r.error("controller.lqr.deflection_weight", "needs tip-deflection outputs: set "
                      "outputs.tip_deflection = true")
    simulator = _checked_simulator(simulator, appendages, manoeuvre, controller, r.error)
    if export.fmu and manoeuvre is None and export.step is None:
        raise r.error("export.step", "missing: without a manoeuvre table the FMU step must be "
                      "given [s]")
    check_flown_scene(r, controller=controller, manoeuvre=manoeuvre, wheels=wheels,
                      sensors=sensors, simulator=simulator, export=export,
                      three_axis=hub.three_axis)
    plots = flown_plots(r, plots, plots_value is True, manoeuvre=manoeuvre, wheels=wheels,
                        simulator=simulator)
    scene = Scene(title=title, source=source or "<dict>", hub=hub, appendages=appendages,
                  fidelity=fidelity, controller=controller, manoeuvre=manoeuvre,
                  outputs=outputs, export=export,
                  report=ReportSpec(plots, equivalence, timeseries), limits=r.limits,
                  simulator=simulator, input_warnings=tuple(r.warnings), wheels=wheels,
                  sensors=sensors)
    _check_cost(r, scene)
    return scene


def _checked_simulator(simulator: SimulatorSpec, appendages, manoeuvre, controller,
                       error) -> SimulatorSpec:
    """A Basilisk run needs a manoeuvre, chain design models and disturbances Basilisk
    applies; it samples at the controller's rate unless told otherwise. ``error(key,
    message)`` makes the exception to raise."""
    if simulator.name != "basilisk":
        return simulator
    if manoeuvre is None:
        raise error("simulator.name", "'basilisk' simulates the manoeuvre: the scene needs "
                    "a manoeuvre table")
    beams = [k for k, a in enumerate(appendages) if a.design == "truth" and a.truth == "beam"]
    if beams:
        raise error(f"appendages[{beams[0]}].design", "Basilisk simulates the design "
                    "chains, and this appendage's design model is the distributed beam "
                    "(design = 'truth'); give it a chain design (design = 'fit' or "
                    "'chain') or drop simulator.name = 'basilisk'")
    if (manoeuvre.disturbance is not None
            and manoeuvre.disturbance.input.endswith("_tip_force")):
        raise error("manoeuvre.disturbance.input", "a tip force is not applied by the "
                    "Basilisk model (it applies the hub's disturbance torque and forces: "
                    "disturbance_torque, force_x, force_y; three axes disturbance_torque_x, "
                    "_y, _z, force_x, _y, _z); choose one of those or drop simulator.name = "
                    "'basilisk'")
    if (simulator.sample_time is not None and controller.sample_time is not None
            and not math.isclose(simulator.sample_time, controller.sample_time, rel_tol=1e-9)):
        raise error("simulator.sample_rate", f"must equal controller.sample_rate = "
                    f"{1.0 / controller.sample_time:.6g} Hz: a digital controller runs as flight "
                    f"software at its own rate; got {1.0 / simulator.sample_time:.6g} Hz (remove "
                    "simulator.sample_rate)")
    if simulator.sample_time is None and controller.sample_time is not None:
        simulator = dataclasses.replace(simulator, sample_time=controller.sample_time)
    return simulator


def read_beam_table(beam: Mapping[str, Any], *, tip: Mapping[str, Any] | None = None,
                    source: str = "command line") -> tuple[BeamSpec, list[str]]:
    """Read and check one beam table as a scene's ``appendages[i].beam`` (units of the file),
    with an optional ``tip`` table (``appendages[i].tip``): the command line's beam options.

    Parameters
    ----------
    beam : mapping
        ``section``, ``length`` [m] and the section's keys (see the scene reference).
    tip : mapping, optional
        ``mass`` [kg], ``inertia`` [kg m^2], ``offset`` [m] of a body at the free end.
    source : str
        Name in messages (``"command line"``).

    Returns
    -------
    BeamSpec, list of str
        The beam and the reader's unit-slip warnings, one line each.

    Raises
    ------
    SceneError
        Naming the key and the problem.
    """
    reader = SceneReader(source)
    tip_spec = _read_tip(reader, tip, "tip") if tip else None
    spec = _read_beam(reader, beam, "beam", tip=tip_spec)
    return spec, list(reader.warnings)


def load_scene(scene: "str | os.PathLike | Mapping[str, Any] | Scene | None" = None, *,
               source: str | None = None, limits: Mapping[str, Any] | None = None,
               base: "str | os.PathLike | None" = None,
               overrides: Mapping[str, Any] | None = None) -> Scene:
    """Read and validate a scene.

    Parameters
    ----------
    scene : path, dict, Scene or None
        A TOML file, the name of an embedded scene (``"two_wings"``, see
        :func:`example_scenes`; when no file of that name exists), a dict with the same
        structure (units of the file: deg, Hz), an already validated Scene (returned as is) or
        None for the embedded default scene.
    source : str, optional
        Name used in error messages for a dict (default ``"<dict>"``).
    limits : mapping, optional
        Work limits that override the defaults and the scene's own ``[limits]`` table
        (names of :class:`~spacecraft.scene.limits.Limits`; the command line's ``--limit``).
    base : path, optional
        The folder that data files named in a dict scene (``modal.file``, ``modal.nastran``,
        ``modal.mass_matrix``) are relative to; default the current folder. A scene file's
        are relative to the file's own folder.
    overrides : mapping, optional
        Key path -> value (units of the file) set in the scene before it is read, so that the
        reader checks them with everything else (the command line's ``--ssp``,
        ``--no-plots``, ``--simulator``...): ``{"export.fmu": True, "report.plots": False}``;
        a value None removes the key. Not for a validated Scene.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        Naming the file, the key path and the problem (also for a missing, unreadable, too
        large or deeply nested file, or bad TOML), or the work limit a scene exceeds.
    """
    if source is not None and not isinstance(source, str):
        raise TypeError(f"source must be a string (the scene's name in messages) or None; got "
                        f"{type(source).__name__}")
    limit_overrides = read_limits(limits, "--limit") if limits is not None else {}
    changes = _checked_overrides(overrides)
    if isinstance(scene, Scene):
        if changes:
            raise TypeError("overrides apply to a scene file, an embedded scene's name or a "
                            "dict (its keys are changed before they are checked); got a "
                            "validated Scene")
        return scene
    if scene is None:
        return load_scene(scene_path("default"), source=source or "default scene",
                          limits=limits, overrides=overrides)
    if isinstance(scene, Mapping):
        name = source or "<dict>"
        folder = Path.cwd() if base is None else Path(base)
        return _guarded(lambda: _read_scene(with_overrides(scene, changes, name), name,
                                            limit_overrides, folder), name)
    if not isinstance(scene, (str, os.PathLike)):
        raise SceneError(f"scene must be a TOML file path, a dict or a Scene; got "
                         f"{shorten(type(scene).__name__)}")
    path = Path(scene)
    if (isinstance(scene, str) and not path.exists() and path.suffix == ""
            and path.parent == Path(".")):
        # an embedded scene's name ("two_wings"), as on the command line
        names = example_scenes()
        if scene in names:
            return load_scene(scene_path(scene), source=source or f"{scene} (embedded scene)",
                              limits=limits, overrides=overrides)
        import difflib

        close = difflib.get_close_matches(scene, names, n=1)
        raise SceneError(f"{shorten(scene)}: no such scene file or embedded scene (embedded: "
                         f"{', '.join(names)})" + (f"; did you mean {close[0]!r}?" if close
                                                   else ""))
    shown = shorten(str(path)) if str(path).isprintable() else shown_value(str(path))
    file_size = limit_overrides.get("file_size", Limits().file_size)
    try:
        with open(path, "rb") as stream:
            text = stream.read(file_size + 1)
    except FileNotFoundError:
        raise SceneError(f"{shown}: no such scene file") from None
    except IsADirectoryError:
        raise SceneError(f"{shown}: is a folder, not a scene file") from None
    except OSError as exc:
        raise SceneError(f"{shown}: cannot read the scene file ({exc.strerror})") from None
    if len(text) > file_size:
        raise SceneError(f"{shown}: the scene file is larger than the limit {file_size} bytes "
                         "(limits.file_size); raise it with --limit file_size=N if you really "
                         "want more")
    try:
        decoded = text.decode("utf-8")
    except UnicodeDecodeError:
        raise SceneError(f"{shown}: not a UTF-8 text file") from None
    name = source or shown

    def parse():
        try:
            data = tomllib.loads(decoded)
        except tomllib.TOMLDecodeError as exc:
            raise SceneError(f"{name}: invalid TOML ({shorten(str(exc), 200)})") from None
        return _read_scene(with_overrides(data, changes, name), name, limit_overrides,
                           path.resolve().parent)
    return _guarded(parse, name)


def _checked_overrides(overrides) -> dict:
    """``overrides`` as a dict of key paths (names joined by dots) to values."""
    if overrides is None:
        return {}
    if not isinstance(overrides, Mapping):
        raise TypeError(f"overrides must be a mapping of key paths to values (e.g. "
                        f"{{'export.fmu': True}}); got {type(overrides).__name__}")
    for path in overrides:
        if not (isinstance(path, str) and all(NAME_PATTERN.fullmatch(p) for p in path.split("."))):
            raise TypeError(f"overrides: a key path is names joined by dots "
                            f"('report.plots'); got {shown_value(path)}")
    return dict(overrides)


def with_overrides(data: Mapping, overrides: Mapping[str, Any], source: str = "") -> dict:
    """A copy of a scene mapping with ``overrides`` (key path -> value, None: remove) set,
    tables made where missing.

    Raises
    ------
    SceneError
        A key path through a value that is not a table, named.
    """
    import copy

    out = copy.deepcopy(dict(data))
    for path, value in overrides.items():
        parts = path.split(".")
        table = out
        for k, part in enumerate(parts[:-1]):
            table = table.setdefault(part, {})
            if not isinstance(table, dict):
                where = ".".join(parts[:k + 1])
                raise SceneError(f"{source}: {where}: must be a table to set {path}; got "
                                 f"{value_kind(table)}")
        if value is None:
            table.pop(parts[-1], None)
        else:
            table[parts[-1]] = value
    return out


def _guarded(read, name: str) -> Scene:
    """Run a reader; nesting deeper than Python's recursion limit is a scene error."""
    try:
        return read()
    except RecursionError:
        raise SceneError(f"{name}: tables or arrays nested too deeply; a scene needs at most "
                         "four levels") from None


def scene_path(name: str) -> Path:
    """Path of an embedded scene (``"default"``, ``"single_boom"``, ``"two_wings"``...)."""
    if not isinstance(name, str):
        raise TypeError(f"name must be the name of an embedded scene (a string); got "
                        f"{type(name).__name__} {shown_value(name)}")
    resource = importlib.resources.files("spacecraft.scene").joinpath("embedded", f"{name}.toml")
    path = Path(str(resource))
    if not path.is_file():
        raise SceneError(f"name: no embedded scene {shown_value(name)}; available: "
                         + ", ".join(example_scenes()))
    return path


def example_scenes() -> list[str]:
    """Names of the embedded scenes."""
    folder = Path(str(importlib.resources.files("spacecraft.scene").joinpath("embedded")))
    return sorted(p.stem for p in folder.glob("*.toml"))


def default_scene(*, limits: Mapping[str, Any] | None = None) -> Scene:
    """The embedded default scene: the paper's steel rod on a 100 kg, 50 kg m^2 hub."""
    return load_scene(None, limits=limits)


def models_scene(hub, names, *, controller, manoeuvre=None, outputs=None, exact: bool = False,
                 source: str = "your models") -> Scene:
    """The question a Python user asks of their own models (``spacecraft.DesignLoop(truth=...)``):
    a scene without appendage tables, whose controller, manoeuvre and outputs are read and
    checked as a scene file's are.

    Parameters
    ----------
    hub : spacecraft.Hub
        The truth model's hub (mass [kg], inertia [kg m^2]: a number, or a 3x3 tensor).
    names : sequence of str
        The appendages' names (the truth model's mounts), for tip-force disturbances.
    controller : mapping or ControllerSpec
        A scene's ``[controller]`` table (file units: Hz for ``sample_rate``) or a validated
        specification.
    manoeuvre : mapping or ManoeuvreSpec, optional
        A scene's ``[manoeuvre]`` table (degrees) or a validated specification.
    outputs : mapping, optional
        A scene's ``[outputs]`` table without ``exact_reference``.
    exact : bool
        An exact spacecraft is given: the loops are judged on it too.
    source : str
        Name in messages.

    Returns
    -------
    Scene
        ``appendages`` empty; fidelity: the models as given, pruned; no FMUs, no plots.

    Raises
    ------
    SceneError
        A table's key or value, named as in a scene file.
    """
    import numpy as np

    three_axis = bool(getattr(hub, "three_axis", False))
    inertia = (tuple(tuple(float(v) for v in row) for row in np.asarray(hub.inertia))
               if three_axis else float(hub.inertia))
    r = SceneReader(source)
    r.three_axis = three_axis
    if not isinstance(controller, ControllerSpec):
        controller = _read_controller(r, controller, "controller")
    if manoeuvre is not None and not isinstance(manoeuvre, ManoeuvreSpec):
        manoeuvre = _read_manoeuvre(r, manoeuvre, "manoeuvre", list(names),
                                    controller.sample_time)
    ot = r.table({} if outputs is None else outputs, "outputs")
    wanted = OutputsSpec(r.boolean(ot, "tip_deflection", "outputs", False),
                         r.boolean(ot, "root_loads", "outputs", False), bool(exact))
    r.done(ot, "outputs", {"tip_deflection", "root_loads"})
    if (controller.lqr is not None and controller.lqr.deflection_weight is not None
            and not wanted.tip_deflection):
        raise r.error("controller.lqr.deflection_weight", "needs tip-deflection outputs: set "
                      "outputs.tip_deflection = true")
    return Scene(title="", source=source, hub=HubSpec(float(hub.mass), inertia), appendages=(),
                 fidelity=FidelitySpec(n_modes=None, tolerance=None), controller=controller,
                 manoeuvre=manoeuvre, outputs=wanted, export=ExportSpec(),
                 report=ReportSpec(plots=(), equivalence=False), limits=r.limits,
                 input_warnings=tuple(r.warnings))
