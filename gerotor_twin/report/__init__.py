"""Model-vs-bench comparison reports (no ROS): ``gerotor-twin report``.

==================  ================================================================
module              responsibility
==================  ================================================================
``data``            load bench recording and twin logs; required topics, clear errors
``analysis``        time grid, plateau detection, error metrics, revolution phase
``figures``         matplotlib figures (PNG bytes)
``html``            the self-contained HTML page
``build``           :func:`build_report` and the ``report`` sub-command
``cli_commands``    registers ``synth-bench``, ``report``, ``run-bag``, ``replay``
==================  ================================================================
"""
