"""``gerotor-twin sweep SPEC.yaml -o RESULTS``: a design study on Dask, resumable, with an HTML summary.

RESULTS (a directory) receives, as the study runs:

=================  ==========================================================
``spec.yaml``      the SPEC as given (provenance)
``manifest.json``  SPEC digest, number of points, parameters, outputs
``points.jsonl``   one record per finished point, appended as it finishes
                   (``id``, ``index``, ``params``, ``status``, ``reason``,
                   ``outputs`` in SI, ``worker``, ``compute_s``)
``results.csv``    the same, sorted by point, the SPEC's outputs as columns
``summary.html``   self-contained page: efficiency map, ripple, parallel coordinates
=================  ==========================================================

``--resume`` continues a study in RESULTS: points already in ``points.jsonl``
are kept, the others run (the SPEC must be the same: its digest is checked).
"""
from __future__ import annotations

import csv
import json
import shutil
import sys
import time
from pathlib import Path
from typing import IO

from ..errors import InputError
from .engine import (Progress, add_engine_arguments, check_engine_args, chunk_size, dask_client, discarded_if_unused,
                     run_tasks)
from .results_store import ResultStore
from .sweep_point import evaluate_point
from .sweep_spec import SweepSpec, load_spec

__all__ = ["run_sweep", "write_outputs", "add_parser", "RESULT_FILES"]

RESULT_FILES = ("spec.yaml", "manifest.json", "points.jsonl", "results.csv", "summary.html")


def _prepare(spec: SweepSpec, out: Path, resume: bool) -> None:
    """Create RESULTS or check that it holds the same study (``--resume``)."""
    manifest = out / "manifest.json"
    digest = spec.digest()
    if manifest.exists():
        if not resume:
            raise InputError("-o", str(out), "a directory without a study, or --resume to continue the one in it")
        have = json.loads(manifest.read_text()).get("spec_digest")
        if have != digest:
            raise InputError("--resume", str(out), "the results of the same SPEC",
                             "the SPEC (or its base config) changed since the study started; use a new -o")
        return
    if out.exists() and not out.is_dir():
        raise InputError("-o", str(out), "a directory (it is a file)")
    out.mkdir(parents=True, exist_ok=True)
    if Path(spec.source).is_file():
        shutil.copyfile(spec.source, out / "spec.yaml")
    manifest.write_text(json.dumps({
        "spec_digest": digest, "spec": spec.source, "title": spec.title, "base_config": spec.base_source,
        "design": spec.design, "points": len(spec.points()), "parameters": [a.name for a in spec.axes],
        "outputs": list(spec.outputs), "model": spec.model, "revolutions": spec.revolutions,
        "operating": spec.operating, "set": spec.set,
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}, indent=2))


def _held(spec: SweepSpec) -> str:
    """The operating point and ``set`` fields held for the whole study, as text."""
    varied = set(_param_names(spec))
    held = {f"operating.{k}": v for k, v in spec.operating.items() if v is not None and f"operating.{k}" not in varied}
    held.update({k: v for k, v in spec.set.items() if k not in varied})
    return "held: " + ", ".join(f"{k} = {v}" for k, v in held.items())


def _param_names(spec: SweepSpec) -> list[str]:
    return [a.name for a in spec.axes]


def write_outputs(spec: SweepSpec, out: Path, records: list[dict], info: list[str]) -> None:
    """``results.csv`` and ``summary.html`` from the records (sorted by point index)."""
    from .sweep_html import sweep_page
    params = _param_names(spec)
    with open(out / "results.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["id", "status", "reason"] + params + list(spec.outputs) + ["worker", "compute_s"])
        for r in records:
            w.writerow([r["id"], r["status"], r["reason"]] + [r["params"].get(p) for p in params]
                       + [r["outputs"].get(o) for o in spec.outputs] + [r.get("worker"), r.get("compute_s")])
    (out / "summary.html").write_text(sweep_page(spec.title, records, params, list(spec.outputs), info),
                                      encoding="utf-8")


def _failure(item: dict, reason: str) -> dict:
    return {"id": item["id"], "index": item["index"], "params": item["params"], "status": "failed",
            "reason": reason, "outputs": {}, "worker": None, "compute_s": None}


def run_sweep(spec: SweepSpec, out, *, scheduler: str | None = None, workers: int | None = None,
              resume: bool = False, progress: IO[str] | None = sys.stderr) -> dict:
    """Run the study ``spec`` into directory ``out``; return counts and timing.

    Parameters
    ----------
    spec : SweepSpec
        The validated SPEC (:func:`~gerotor_twin.offline.sweep_spec.load_spec`).
    out : path
        RESULTS directory (see the module docstring).
    scheduler : str, optional
        Dask scheduler address; default an embedded LocalCluster with ``workers`` processes (all cores).
    resume : bool
        Continue the study already in ``out``.
    progress : text stream or None
        Progress line with ETA.

    Returns
    -------
    dict
        ``points``, ``ok``, ``failed``, ``computed`` (this run), ``kept`` (from before), ``wall_s``
        (all of it [s]), ``run_s`` (from the first task submitted to the last result [s]), ``workers``.
    """
    out = Path(out)
    check_engine_args(scheduler, workers)
    with discarded_if_unused(out, RESULT_FILES, "points.jsonl"):
        _prepare(spec, out, resume)
        points = spec.points()
        t0 = time.monotonic()
        with ResultStore(out / "points.jsonl") as store:
            kept = len(store)
            bar = Progress("sweep", len(points), done=sum(p["id"] in store for p in points), stream=progress)
            if len(store) < len(points):
                with dask_client(scheduler, workers) as client:
                    n_workers = len(client.scheduler_info()["workers"])
                    t_run = time.monotonic()
                    todo = sum(p["id"] not in store for p in points)
                    run_tasks(client, evaluate_point, spec.task(), points, store, progress=bar, failure=_failure,
                              key_prefix=f"sweep-{spec.digest()[:12]}", chunk=chunk_size(todo, n_workers))
                    run_s = time.monotonic() - t_run
            else:
                n_workers, run_s = 0, 0.0
            bar.close()
            records = sorted(store.records.values(), key=lambda r: r["index"])
    wall = time.monotonic() - t0
    ok = sum(r["status"] == "ok" for r in records)
    info = [f"{len(records)} of {len(points)} points: {ok} computed, {len(records) - ok} failed "
            f"({spec.design} design, model {spec.model}, base {spec.base_source})",
            _held(spec),
            f"{len(records) - kept} points this run in {wall:.1f} s on {n_workers} worker(s)"
            + (f"; {kept} kept from before (--resume)" if kept else "")]
    write_outputs(spec, out, records, info)
    return {"points": len(points), "ok": ok, "failed": len(records) - ok, "computed": len(records) - kept,
            "kept": kept, "wall_s": wall, "run_s": run_s, "workers": n_workers}


def cmd_sweep(args) -> int:
    spec = load_spec(args.spec)
    res = run_sweep(spec, args.output, scheduler=args.scheduler, workers=args.workers, resume=args.resume,
                    progress=None if args.quiet else sys.stderr)
    out = Path(args.output)
    print(f"sweep '{spec.title}': {res['points']} points, {res['ok']} ok, {res['failed']} failed "
          f"({res['computed']} computed in {res['wall_s']:.1f} s on {res['workers']} worker(s), {res['kept']} kept)")
    print(f"wrote {out / 'points.jsonl'}, {out / 'results.csv'}, {out / 'summary.html'}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("sweep", help="design study: vary config fields / operating point / bearing model on Dask",
                       description="Run every point of a SPEC (YAML: base pump config, parameters as lists, "
                                   "ranges, or Latin-hypercube / Sobol samples, outputs) to periodic steady "
                                   "state on a Dask cluster (embedded by default), write results incrementally "
                                   "and an HTML summary. See docs/sweep.md.")
    p.add_argument("spec", help="SPEC YAML file")
    p.add_argument("-o", "--output", required=True, help="RESULTS directory")
    add_engine_arguments(p)
    p.add_argument("--resume", action="store_true", help="continue the study in RESULTS (same SPEC)")
    p.set_defaults(func=cmd_sweep)
