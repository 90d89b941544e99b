"""gerotor_twin — real-time digital twin of a Gerotor pump.

Lumped-parameter (0D) model of [1] with the micro-motion of the outer gear
treated as a journal bearing under dynamic load, wrapped in a ROS 2 node,
MCAP logging, bag replay and model-vs-bench reports.

=======================  ==================================================
module                   responsibility
=======================  ==================================================
``config``               typed, validated pump / fluid / operating config (YAML);
                         ``config_oil``: its ``oil``, ``mixture``, ``fluid_model``;
                         ``config_notes``: values far from their default, changed
                         and removed keys (warnings, not errors)
``errors``               :class:`InputError`: field, value, allowed range
``resources``            the one lookup of the files beside the code (config,
                         pump family, launch, layouts, bags): source tree,
                         ament index or ``share/gerotor_twin`` of the prefix
``units``                rpm/bar/L-min conversions, used only at the edges
``geometry``             gerotor profiles, chambers (V, dV/dθ, l_x, l_y, arms),
                         ports, tooth-tip gaps (h, le, v_r), lateral gaps,
                         tables over the shaft angle
``hydraulics``           oil vs temperature, fluid (β(p) Eq. (23)), oil–air–vapour
                         mixture, state equation ln ρ ⇄ p (both models),
                         orifice (Eq. (21), Cd(λ)), leakages (sec. 3.1–3.4)
``bearing``              outer gear as a journal bearing: mobility, short
                         bearing (Method 1), FDM Reynolds, fixed centre;
                         ``registry``: the model names and the factory
``model``                the pump: ``params`` (config → kernel structures),
                         ``flows`` (right-hand side, Eq. (20)), ``contact``
                         (sec. 3.7), ``loads`` (Eqs. (24)–(27)), ``kernel``
                         (stepper), ``pump`` (``PumpModel.advance``),
                         ``steady``, ``volumetric`` (edge losses), ``accuracy``,
                         ``bench``
``twin``                 ROS-free twin core: inputs, clock driver, outputs,
                         diagnostics (shared by the node and run-bag)
``io``                   MCAP read/write of ROS 2 messages without rclpy
``offline``              run-bag: the twin core over a recording; sweeps,
                         fleets of recordings (Dask)
``calibration``          fit the twin's physical parameters to plateaus of
                         recordings or a pump's steady map; identifiability,
                         cross-validated choice of the parameter set
``report``               bench-vs-twin alignment, metrics, figures, HTML
``paper``                section 4 of [1]: tables 3–5, calibration, figures
``bench_emulator``       synth-bench: a pump that differs from the twin,
                         seen through sensor models
``ros``                  rclpy node, replay, demo, bench node: the only
                         modules importing rclpy
``cli``                  the ``gerotor-twin`` command
=======================  ==================================================

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear" (see ``../shared/paper``).
"""

__version__ = "0.1.0"
