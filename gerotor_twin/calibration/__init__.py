"""Calibration of the twin's physical parameters from steady operating points.

One entry point, :func:`.command.calibrate_records`, fed by the plateaus of bench recordings
(:mod:`.plateaus`, ``gerotor-twin calibrate --bench``) or the rows of a pump's published steady
map (:mod:`.pump_map`, ``--map``): the fittable parameters and the model at one point
(:mod:`.fit_model`), the least-squares fit (:mod:`.fit`), what the data can determine
(:mod:`.identifiability`), the choice of the parameter set by cross-validation with an empirical
baseline and the verdict against the nominal twin (:mod:`.selection`, :mod:`.command`), the prediction
interval with the model-form error seen held out (:mod:`.prediction`), the HTML page (:mod:`.report`);
maps made with the twin at known parameters (:mod:`.map_synth`), steady plateaus of a bench pump that differs
from the twin in form (:mod:`.bench_steady`) and the benchmark on maps with physics the twin lacks
(:mod:`.map_bench`, ``gerotor-twin bench maps``).
"""
