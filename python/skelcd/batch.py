"""skelcd.batch — many clips checked as tasks on a Dask distributed cluster (docs/python.md).

What ``skelcd check MODEL… -o DIR --all-clips`` does on one machine, spread over the workers of a
cluster: models × clips × methods become one task each; each task writes one log,
``DIR/MODEL-CLIP.h5`` as the command line names it (``MODEL-CLIP-METHOD.h5`` when several
methods are asked for). A model that fails to load or a clip that fails to check is collected with
its message, never raised. Running the same batch again skips every task whose log is already
complete and matches the task, so a batch cut short is resumed by starting it again::

    from skelcd import batch
    result = batch.run(["assets/characters/*.glb"], "logs", all_clips=True)          # this machine
    result = batch.run(models, "/shared/logs", scheduler="tcp://HOST:8786")       # a cluster
    for f in result.failures:
        print(f["model"], f["clip"], f["error"])

From a shell: ``python3 -m skelcd.batch MODEL… -o DIR [--all-clips] [--scheduler tcp://HOST:8786]``.
The workers open the models and write the logs themselves: on several machines the paths must
name the same files everywhere (a shared folder).
"""

from __future__ import annotations

import argparse
import glob
import os
import re
import sys
from dataclasses import dataclass, field
from typing import Iterable, Optional, Sequence

from . import _skelcd

__all__ = ["BatchResult", "log_name", "run", "main"]


# --- naming: the command line's own (tools/engine/check_engine.hpp, batch_log_name) ----------------------

def _is_generator_spec(model: str) -> bool:
    return model.startswith("gen:")


def _has_glob(model: str) -> bool:
    return not _is_generator_spec(model) and re.search(r"[*?\[]", model) is not None


_file_name_part = _skelcd.file_name_part


def log_name(model: str, clip: str) -> str:
    """MODEL-CLIP (without .h5), as ``skelcd check``'s batch names a log: the model file's stem
    (a frame sequence's folder, a generator spec as written), then the clip when there is one."""
    return _skelcd.log_name(os.fspath(model), clip or "")


def _expand_models(models: Iterable[str]) -> list:
    """Quoted globs expanded as the command line does: a glob matching only OBJ/PLY files (or
    nothing) stays one argument, a frame sequence."""
    out = []
    for model in models:
        model = os.fspath(model)
        if not _has_glob(model):
            out.append(model)
            continue
        matches = sorted(glob.glob(model))
        frames = all(os.path.isfile(m) and m.lower().endswith((".obj", ".ply")) for m in matches)
        if frames:
            out.append(model)
        else:
            out.extend(matches)
    return out


# --- the tasks (run on the workers) ---------------------------------------------------------------

def _load(model: str, load_options: dict):
    import skelcd
    return skelcd.load(model, **load_options)


def _clips_task(model: str, load_options: dict) -> dict:
    """The usable clips of `model`, or the error that kept it from loading."""
    try:
        return {"clips": _load(model, load_options).clips, "error": None}
    except Exception as e:  # every failure is reported, not raised (a broken file is data)
        return {"clips": [], "error": str(e) or type(e).__name__}


def _complete_log(path: str, task: dict) -> bool:
    """True when `path` is a complete, undamaged log of this very task (the batch resumes)."""
    if not os.path.isfile(path):
        return False
    import skelcd
    try:
        log = skelcd.read_log(path)
    except Exception:
        return False
    h = log.header
    wanted = task["options"]
    fps = float(wanted.get("fps") or 0)
    frames = skelcd._frames_text(wanted.get("frames"))
    first, _, last = frames.partition(":") if ":" in frames else (frames, "", frames)
    return (bool(h["complete"]) and not log.damage and len(log.rows) == h["planned_rows"]
            and h["input_path"] == task["model"]
            and (not task["clip_asked"] or h["clip"] == task["clip_asked"])
            and h["method"] == task["method"] and h["accuracy"] == wanted["accuracy"]
            and h["query"] == wanted["query"]
            and h["min_separation"] == wanted["min_separation"]
            and (fps == 0 or abs(h["fps"] - fps) <= 1e-9 * fps)
            and h["first_sample"] == int(first or 0) and (not last or h["last_sample"] == int(last)))


def _check_task(task: dict) -> dict:
    """Checks one clip into its log; 'skipped' when a complete log of it exists already."""
    import skelcd
    outcome = {key: task[key] for key in ("model", "clip", "method", "log")}
    if _complete_log(task["log"], task):
        return {**outcome, "status": "skipped", "error": None, "summary": None}
    try:
        model = _load(task["model"], task["load_options"])
        result = skelcd.check(model, clip=task["clip_asked"] or None, method=task["method"],
                              log=task["log"], **task["options"])
        summary = {k: v for k, v in result.summary.items() if k != "worst"}
        return {**outcome, "status": "done", "error": None, "summary": summary}
    except Exception as e:
        return {**outcome, "status": "failed", "error": str(e) or type(e).__name__, "summary": None}


# --- the client ----------------------------------------------------------------------------------

@dataclass
class BatchResult:
    """What a batch did. Each entry of done/skipped/failures is a dict with model, clip, method,
    log and, for done, the ``check --json`` summary; failures carry ``error``, the one-line
    message (a model that did not load has clip "" unless one was asked for, and no log)."""

    done: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    failures: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.failures

    def describe_failure(self, failure: dict) -> str:
        """"MODEL (clip C): fault", as ``skelcd check``'s batch prints it."""
        model, error = failure["model"], failure["error"]
        where = model + (f" (clip {failure['clip']})" if failure["clip"] else "")
        return where + error[len(model):] if error.startswith(model + ":") else f"{where}: {error}"


class _Counter:
    """A one-line counter on stderr, for batches whose output is not a terminal."""

    def __init__(self, total: int, stream=None):
        self.total, self.done, self.stream = total, 0, stream or sys.stderr

    def update(self, outcome: dict) -> None:
        self.done += 1
        print(f"batch {self.done}/{self.total} {outcome['status']:7} {os.path.basename(outcome['log'])}",
              file=self.stream, flush=True)


def _client(scheduler, n_workers: Optional[int]):
    """A Dask client: of `scheduler` (an address or a Client), else of a LocalCluster of one
    single-threaded worker process per core (or n_workers). Returns (client, cluster to close)."""
    from dask.distributed import Client, LocalCluster
    if isinstance(scheduler, Client):
        return scheduler, None, False
    if scheduler:
        return Client(scheduler), None, True
    cluster = LocalCluster(n_workers=n_workers or os.cpu_count() or 1, threads_per_worker=1,
                           processes=True, dashboard_address=None)
    return Client(cluster), cluster, True


def run(models: Sequence, out_dir, *, clips: Optional[Sequence[str]] = None, all_clips: bool = False,
        methods: Sequence[str] = ("auto",), scheduler=None, n_workers: Optional[int] = None,
        progress: Optional[bool] = None, trajectory=None, srdf=None, package_path=(),
        **check_options) -> BatchResult:
    """Checks models × clips × methods on a Dask cluster, one log per clip in `out_dir`.

    models: paths, quoted globs ("dir/*.glb") or generator specs, as ``skelcd check`` takes them.
    clips: clip names to check in every model; all_clips: every usable clip of each model;
        neither: each model's first clip (the command line's default).
    methods: culling methods; with more than one the log names end in -METHOD.
    scheduler: None (a LocalCluster of worker processes on this machine, n_workers of them, one
        per core by default), a scheduler address "tcp://HOST:8786", or a dask Client.
    progress: True or None: dask's progress bar when stdout is a terminal, else one line per
        finished task on stderr; False: quiet.
    trajectory, srdf, package_path: load options for URDF robots (as for skelcd.load).
    check_options: the other options of skelcd.check (fps, frames, accuracy, query,
        min_separation, threads, gamma, seed, segmentation) — the same for every task.
    Failures are collected in BatchResult.failures with their messages, never raised; a task whose
    complete log exists already (same model, clip, method, accuracy, query, min_separation, fps
    and frames) is skipped.
    """
    if clips and all_clips:
        raise ValueError("clips and all_clips: give one of them")
    models = _expand_models(models)
    out_dir = os.fspath(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    load_options = {"trajectory": trajectory, "srdf": srdf, "package_path": list(package_path)}
    options = {"accuracy": "conservative", "query": "both", "min_separation": 0.0, "threads": 1,
               **check_options}
    progress = progress is None or progress
    bar = progress and sys.stdout.isatty()  # dask's bar draws on stdout

    from dask.distributed import as_completed
    from dask.distributed import progress as dask_progress
    client, cluster, close = _client(scheduler, n_workers)
    result = BatchResult()
    try:
        # First wave: which clips each model has (the log names need the first clip's name).
        listed = client.gather(client.map(_clips_task, models, load_options=load_options, pure=False))
        tasks, names = [], set()
        for model, found in zip(models, listed):
            if found["error"] is not None:
                result.failures.append({"model": model, "clip": clips[0] if clips and len(clips) == 1 else "",
                                        "method": methods[0], "log": None, "error": found["error"]})
                continue
            if all_clips and found["clips"]:
                asked = list(found["clips"])
            else:
                asked = list(clips) if clips else [""]
            for clip in asked:
                clip_name = clip or (found["clips"][0] if found["clips"] else "")
                for method in methods:
                    base = log_name(model, clip_name) + (f"-{_file_name_part(method)}" if len(methods) > 1 else "")
                    name, k = base, 2
                    while name in names:
                        name, k = f"{base}-{k}", k + 1
                    names.add(name)
                    tasks.append({"model": model, "clip": clip_name, "clip_asked": clip, "method": method,
                                  "log": os.path.join(out_dir, name + ".h5"), "options": options,
                                  "load_options": load_options})

        # Second wave: one task per log; bigger logs have no priority, the scheduler balances.
        futures = client.map(_check_task, tasks, pure=False)
        if bar:
            dask_progress(futures, notebook=False)
        counter = _Counter(len(futures)) if progress and not bar else None
        index = {future.key: i for i, future in enumerate(futures)}
        outcomes = {}
        for future in as_completed(futures):
            task = tasks[index[future.key]]
            try:
                outcome = future.result()
            except Exception as e:  # the worker died (a crash in a library, killed for memory)
                outcome = {**{k: task[k] for k in ("model", "clip", "method", "log")}, "status": "failed",
                           "error": f"{task['model']}: the worker failed: {e}", "summary": None}
            outcomes[task["log"]] = outcome
            if counter:
                counter.update(outcome)
        for task in tasks:  # in task order, not completion order
            outcome = outcomes[task["log"]]
            {"done": result.done, "skipped": result.skipped, "failed": result.failures}[outcome["status"]].append(outcome)
    finally:
        if close:
            client.close()
        if cluster is not None:
            cluster.close()
    return result


def main(argv: Optional[Sequence[str]] = None) -> int:
    """``python3 -m skelcd.batch``: the command-line face of run()."""
    parser = argparse.ArgumentParser(prog="python3 -m skelcd.batch", description=__doc__.split("\n\n")[0])
    parser.add_argument("models", nargs="+", help="model files, quoted globs or gen: specs")
    parser.add_argument("-o", "--output-dir", required=True, help="folder for the logs (MODEL-CLIP.h5)")
    parser.add_argument("--clip", action="append", help="clip to check (repeatable; default: the first)")
    parser.add_argument("--all-clips", action="store_true", help="every usable clip of each model")
    parser.add_argument("--method", action="append", help="culling method (repeatable; default auto, as skelcd check)")
    parser.add_argument("--accuracy", default="conservative")
    parser.add_argument("--query", default="both")
    parser.add_argument("--fps", type=float, default=0.0)
    parser.add_argument("--scheduler", help="scheduler address tcp://HOST:8786 (default: this machine)")
    parser.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    args = parser.parse_args(argv)
    result = run(args.models, args.output_dir, clips=args.clip, all_clips=args.all_clips,
                 methods=args.method or ["auto"], scheduler=args.scheduler, n_workers=args.workers,
                 accuracy=args.accuracy, query=args.query, fps=args.fps)
    checks = len(result.done) + len(result.skipped) + len(result.failures)
    print(f"batch     {checks} checks: {len(result.done)} done, {len(result.skipped)} skipped "
          f"(complete logs), {len(result.failures)} failed")
    for failure in result.failures:
        print("FAILED    " + result.describe_failure(failure))
    return 0 if result.ok else 1


if __name__ == "__main__":
    sys.exit(main())
