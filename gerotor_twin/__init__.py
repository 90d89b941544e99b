"""gerotor_twin — real-time digital twin of a Gerotor pump.

Lumped-parameter (0D) model of [1] with the micro-motion of the outer gear
treated as a journal bearing under dynamic load, wrapped in a ROS 2 node,
MCAP logging, bag replay and model-vs-bench reports.

=======================  ==================================================
module                   responsibility
=======================  ==================================================
``config``               typed, validated pump / fluid / operating config (YAML)
``errors``               :class:`InputError`: field, value, allowed range
``units``                rpm/bar/L-min conversions, used only at the edges
``geometry``             gerotor profiles, chambers (V, dV/dθ, l_x, l_y, arms),
                         ports, tooth-tip gaps (h, le, v_r), lateral gaps,
                         overlap/contact of the displaced gears (sec. 3.7)
``hydraulics``           fluid (β(p) eq. 23, ρ(p)), orifice (eq. 21, Cd(Re)),
                         leakages (sec. 3.1–3.4)
``bearing``              outer gear as a journal bearing: mobility, short
                         bearing (Method 1), FDM Reynolds, fixed centre
``model``                the pump: state, right-hand side (eq. 20), loads
                         (eqs. 24–27), the stepper ``advance()``, results
``io``                   MCAP read/write of ROS 2 messages without rclpy
``report``               bench-vs-twin alignment, metrics, figures, HTML
``ros``                  rclpy node, replay: the only modules importing rclpy
``cli``                  the ``gerotor-twin`` command
=======================  ==================================================

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear" (see ``../shared/paper``).
"""

__version__ = "0.1.0"
