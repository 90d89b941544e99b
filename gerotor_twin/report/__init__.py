"""Model-vs-bench comparison reports (no ROS): ``gerotor-twin report`` (docs/report.md).

==================  ================================================================
module              responsibility
==================  ================================================================
``data``            load bench recording and twin logs; required topics, clear errors
``analysis``        time grid, plateau detection, error metrics, revolution phase
``acceptance``      acceptance criterion (tolerances, options, YAML) and verdicts
``context``         :class:`ReportContext`: everything a page block draws from
``layout``          ``PAGE``: the ordered list of block functions (add plots here)
``panels``          block specs (TimeSeries, Table, Image), min/max decimation
``timeseries``      the interactive time plots; ``bench_panel`` (raw under means)
``health_panels``   the health monitor's plots (reference efficiency, leakage factor, alarms) and fault timeline
``tables``          tables of the page, their CSV text, the aligned-series CSV
``figures``         matplotlib figures (PNG bytes), readable style, small multiples
``provenance``      files, pump config and calibration source, software, model
``interactive``     vendored uPlot and ``report.js`` inlined; panel data as JSON
``html``            the self-contained HTML page
``build``           :func:`build_report` and the ``report`` sub-command
==================  ================================================================

``vendor/uplot/``: uPlot 1.6.32 (MIT), unmodified, with ``LICENSE`` and ``VENDORED.md``.
"""
