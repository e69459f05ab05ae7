"""Many parts at once: a folder of meshes, a robot's links, a batch of shapes (issue 25).

:func:`pack_many` runs :func:`ndpack.pack` on each part where the engine puts it: a local pool of
processes (the default), a Dask cluster (``client=``), or this process (``workers=1``). Each part
is independent, so one that fails (a broken file, a bad shape) is reported and the others go on::

    import ndpack as nd
    result = nd.pack_many(["cow.obj", "fandisk.obj", "box:dim=3"], n=2000, out="packed/")
    print(result.summary())

With ``out`` every part is written as ``out/<name>.<format>`` as soon as it is made, and
``out/manifest.json`` lists every part (source, file, status, error, spheres, fill, seconds,
params); a second run skips the parts the manifest says are done with the same parameters and
whose file still loads, so an interrupted or partly failed run is resumed, not redone.

A process pool starts its workers by ``spawn`` (numba and ``fork`` do not mix), which imports the
calling script again in each worker: in a script, call :func:`pack_many` under
``if __name__ == "__main__":``, as any process pool or Dask ``LocalCluster`` needs.
"""

from __future__ import annotations

import json
import os
import re
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ..drivers.greedy.protosphere import pack
from ..errors import NdpackError, ParameterError
from ..io import FORMATS, check, load, save
from ..io.shape_sources import describe, is_mesh_file, load_shape
from .workers import Workers

#: The manifest's name inside ``out``.
MANIFEST = "manifest.json"
#: A part's status: packed now, packed by an earlier run (kept), failed, or not finished (Ctrl-C).
DONE, SKIPPED, FAILED, PENDING = "done", "skipped", "failed", "pending"


@dataclass
class ManyResult:
    """What :func:`pack_many` made.

    Attributes
    ----------
    parts : list of dict
        One record per source, in the order of ``sources``, as in the manifest: ``name``,
        ``source``, ``file`` (None without ``out``), ``status`` (``"done"``, ``"skipped"``,
        ``"failed"`` or ``"pending"`` where a Ctrl-C stopped the run first), ``error`` (one
        line, or None), ``spheres``, ``fill``, ``stop_reason``, ``seconds`` and ``params``
        (``n``, the ``pack`` options asked for that differ from its defaults, ``holes`` and
        ``sign`` where given: what a re-run compares).
    packings : Mapping of str to Packing
        The packed parts by name (done or skipped): kept in memory without ``out``, else loaded
        from their files when first asked for. A part given as a path comes back without its
        ``shape`` (as from a file: ``verify(packing, load_shape(packing.params["source"]))``);
        a part given as a shape object keeps it.
    out : Path or None
        The output folder.
    interrupted : bool
        Whether Ctrl-C stopped the run (the parts it finished are kept).
    """

    parts: list
    packings: Mapping = field(default_factory=dict, repr=False)
    out: Path | None = None
    interrupted: bool = False

    @property
    def failed(self) -> list:
        """The records of the parts that failed."""
        return [part for part in self.parts if part["status"] == FAILED]

    @property
    def ok(self) -> bool:
        """Whether every part is packed (now or by an earlier run)."""
        return all(part["status"] in (DONE, SKIPPED) for part in self.parts)

    def summary(self) -> str:
        """One line per part (name, status, spheres, fill, seconds, file or error), then the totals."""
        width = max((len(part["name"]) for part in self.parts), default=4)
        lines = []
        for part in self.parts:
            head = f"{part['name']:<{width}}  {part['status']:<7}"
            if part["status"] in (DONE, SKIPPED):
                where = f"  {part['file']}" if part["file"] else ""
                lines.append(f"{head}  {part['spheres']:>6} spheres  fill {part['fill']:.4f}  "
                             f"{part['seconds']:7.2f} s{where}")
            else:
                lines.append(f"{head}  {part['error'] or ''}".rstrip())
        counts = {status: sum(part["status"] == status for part in self.parts)
                  for status in (DONE, SKIPPED, FAILED, PENDING)}
        said = ", ".join(f"{count} {status}" for status, count in counts.items() if count)
        seconds = sum(part["seconds"] or 0.0 for part in self.parts if part["status"] == DONE)
        where = f"; manifest {self.out / MANIFEST}" if self.out is not None else ""
        stopped = "; interrupted (Ctrl-C)" if self.interrupted else ""
        lines.append(f"total: {len(self.parts)} parts: {said or 'none'}; {seconds:.2f} s packing (summed over "
                     f"parts){where}{stopped}")
        return "\n".join(lines)


def pack_many(sources, n: int = 1000, *, out=None, format: str = "npz", client=None, workers: int | None = None,
              gpus=None, progress: bool | None = None, holes: str | None = None, sign: str | None = None,
              **pack_options) -> ManyResult:
    """Pack each of ``sources`` with :func:`ndpack.pack`, in parallel; a failing part does not stop the others.

    Parameters
    ----------
    sources : sequence of Oracle, str or Path
        The parts: shapes (any ndpack oracle; picklable, as they travel to the workers) or
        strings and paths that :func:`~ndpack.io.shape_sources.load_shape` reads (mesh files,
        built-in specs such as ``box:dim=3``, scripts), loaded in the worker so that a big mesh
        is not shipped.
    n : int
        Spheres per part.
    out : str or Path, optional
        A folder (made if missing) for ``<name>.<suffix>`` per part and ``manifest.json``. The
        name is the file's stem, a spec's text (``box_dim_3``), or ``part<i>`` for a shape
        object; clashing names get ``-2``, ``-3``, ... Without ``out`` the packings are kept in
        memory. With it, a part the manifest says is done with the same ``n`` and options, whose
        file still loads, is skipped.
    format : str
        The output format's name (see :func:`ndpack.io.table`); its first suffix names the files.
    client : dask.distributed.Client, optional
        Run the parts on this Dask cluster (``client.submit``); else on a local process pool.
    workers : int, optional
        The local pool's processes (default: ``os.cpu_count()``); 1 runs the parts here, one by
        one, with no pool (for debugging). Ignored with ``client``.
    gpus : sequence of int, optional
        Spread the local workers over these GPUs in turn, each seeing one as ``cuda:0`` (pass
        ``device="cuda:0"`` and a GPU backend).
    progress : bool, optional
        A progress bar over the parts; by default only when stderr is a terminal.
    holes, sign : str, optional
        For the sources that are mesh files: as for :class:`~ndpack.TriangleMesh`.
    **pack_options
        Passed to :func:`ndpack.pack` for every part (``seed``, ``grid``, ``mode``, ``backend``,
        ...), with ``progress=False``.

    Returns
    -------
    ManyResult
        ``parts`` in the order of ``sources``; ``ok`` says whether all are packed. Ctrl-C stops
        the pool and returns what finished (``interrupted``); with ``out`` it is written.
    """
    from tqdm.auto import tqdm

    if isinstance(sources, (str, os.PathLike)):
        raise ParameterError(f"sources is a list of parts, got the one string {str(sources)!r}: pass [source], or "
                             f"sorted(glob.glob('folder/*.stl')) for a folder")
    sources = list(sources)
    if "progress" in pack_options or "on_round" in pack_options:
        raise ParameterError("pack_many shows its own progress over parts, and a part's on_round callback cannot "
                             "travel to a worker: leave progress= and on_round= out of the pack options")
    if format not in FORMATS:
        raise ParameterError(f"unknown format {format!r}: one of {', '.join(FORMATS)}")
    suffix = FORMATS[format].suffixes[0]
    check(Path(f"part{suffix}"), format)  # a format that cannot be written (medial, ...) is refused now
    params = _asked(n, pack_options)
    params.update({key: value for key, value in (("holes", holes), ("sign", sign)) if value is not None})
    names = _names(sources)
    folder = _folder(out) if out is not None else None
    parts: list[dict] = [
        dict(name=name, source=_label(source), file=None, status=PENDING, error=None, spheres=None, fill=None,
             stop_reason=None, seconds=None, params=dict(params)) for name, source in zip(names, sources)]
    if folder is not None:
        for part, source in zip(parts, sources):
            part["file"] = str(folder / f"{part['name']}{suffix}")
            if isinstance(source, (str, os.PathLike)) and Path(source).expanduser().resolve() == Path(
                    part["file"]).resolve():
                raise ParameterError(f"{part['file']} would overwrite its source: write to another folder or format")
        _resume(parts, folder / MANIFEST, format)
    packings: dict = {}
    todo = [i for i, part in enumerate(parts) if part["status"] != SKIPPED]
    tasks = {i: _Task(sources[i], n, pack_options, parts[i]["file"], format, holes, sign) for i in todo}

    def finished(i: int, record: dict, packing) -> None:
        parts[i].update(record)
        if packing is not None:
            if not isinstance(sources[i], (str, os.PathLike)):
                packing.shape = sources[i]  # the caller's own object, not the copy that travelled
            packings[parts[i]["name"]] = packing
        if folder is not None:
            _write_manifest(folder / MANIFEST, parts, format)

    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=len(parts), initial=len(parts) - len(todo), unit="part", disable=not show, dynamic_ncols=True)
    if folder is not None:
        _write_manifest(folder / MANIFEST, parts, format)  # the plan, before any part: an early Ctrl-C keeps it
    interrupted = False
    try:
        with Workers(workers, client, most=len(tasks), gpus=gpus) as pool:
            for i, result, error in pool.run(_pack_one, tasks):
                finished(i, *(result if error is None else (_failure(error), None)))
                bar.update()
    except KeyboardInterrupt:  # the pool is stopped; what finished is kept
        interrupted = True
    finally:
        bar.close()
    made = {part["name"]: packings.get(part["name"]) for part in parts  # in the order of sources
            if part["status"] in (DONE, SKIPPED)}
    kept: Mapping = made if folder is None else _Lazy(made, {part["name"]: (part["file"], format) for part in parts})
    return ManyResult(parts=parts, packings=kept, out=folder, interrupted=interrupted)


# ------------------------------------------------------------------------------- the work of one part
@dataclass
class _Task:
    """One part's work, as it travels to a worker (picklable: a path, or the shape object)."""

    source: object
    n: int
    options: dict
    file: str | None
    format: str
    holes: str | None = None
    sign: str | None = None


def _pack_one(_shared, task: _Task) -> tuple[dict, object]:
    """Pack one part (in a worker; nothing is shared): its record's new fields, and the packing where it is not
    written (else None). Any error becomes the record's one-line ``error``."""
    started = time.perf_counter()
    try:
        source = task.source
        if isinstance(source, (str, os.PathLike)):
            text = str(source)
            mesh = is_mesh_file(text)
            shape = load_shape(text, task.holes if mesh else None, task.sign if mesh else None)
        else:
            shape = source
        packing = pack(shape, n=task.n, progress=False, **task.options)
        if packing.stop_reason == "interrupted":  # Ctrl-C in this process (workers=1): stop the run
            raise KeyboardInterrupt
        if isinstance(source, (str, os.PathLike)):
            packing.params["source"] = describe(str(source))  # so that `ndpack verify` finds the shape
            if task.sign is not None and mesh:
                packing.params["sign"] = task.sign
        if task.file is not None:
            # Written beside its name and renamed: a killed run never leaves a half file under it.
            final = Path(task.file)
            partial = final.with_name(f".{final.stem}.partial{final.suffix}")
            save(packing, partial, task.format)
            os.replace(partial, final)
        packing.shape = None  # not shipped back: the caller has it (an object) or its file (a path)
        record = dict(status=DONE, error=None, spheres=len(packing), fill=_finite(packing.fill),
                      stop_reason=packing.stop_reason, seconds=round(time.perf_counter() - started, 3))
        return record, None if task.file is not None else packing
    except Exception as error:  # noqa: BLE001 - any failure of one part is reported, and the others go on
        return _failure(error, time.perf_counter() - started), None


def _failure(error: BaseException, seconds: float | None = None) -> dict:
    message = " ".join(str(error).split())
    if not isinstance(error, NdpackError):
        message = f"{type(error).__name__}: {message}" if message else type(error).__name__
    return dict(status=FAILED, error=message, spheres=None, fill=None, stop_reason=None,
                seconds=None if seconds is None else round(seconds, 3))


def _finite(value: float) -> float | None:
    """A fill for JSON: None where unknown (NaN)."""
    return float(value) if value == value else None


# --------------------------------------------------------------------------- names, folder, manifest
def _label(source) -> str:
    """A source as the manifest records it: the string, or the shape's repr (cut short)."""
    if isinstance(source, (str, os.PathLike)):
        return str(source)
    text = " ".join(repr(source).split())
    return text if len(text) <= 200 else text[:197] + "..."


def _names(sources: list) -> list[str]:
    """A file name per source (``cow`` for ``parts/cow.obj``, ``box_dim_3`` for ``box:dim=3``,
    ``part<i>`` for a shape object); clashes (case aside) get ``-2``, ``-3``, ..."""
    names, taken = [], set()
    for i, source in enumerate(sources):
        if isinstance(source, (str, os.PathLike)):
            text = str(source).strip()
            base = Path(text).stem if is_mesh_file(text) or text.lower().endswith(".py") else text
            base = re.sub(r"[^\w.-]+", "_", base).strip("_.") or f"part{i}"
        else:
            base = f"part{i}"
        name, k = base, 1
        while name.casefold() in taken or name == MANIFEST.partition(".")[0]:
            k += 1
            name = f"{base}-{k}"
        taken.add(name.casefold())
        names.append(name)
    return names


def _folder(out) -> Path:
    folder = Path(out).expanduser()
    if folder.exists() and not folder.is_dir():
        raise ParameterError(f"out={str(out)!r} is a file: pack_many writes a folder of parts; name a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise ParameterError(f"cannot make the folder {out}: {error.strerror or error}") from None
    return folder


def _asked(n, options: dict) -> dict:
    """``n`` and the pack options that differ from ``pack``'s defaults, as JSON keeps them: the
    params a re-run compares (so ``ndpack pack``, which passes every option, and a call that passes
    few agree)."""
    import inspect

    defaults = {name: _jsonable(parameter.default) for name, parameter in inspect.signature(pack).parameters.items()
                if parameter.default is not parameter.empty}
    asked = {name: _jsonable(value) for name, value in options.items()}
    return {"n": _jsonable(n), **{name: value for name, value in asked.items()
                                  if name not in defaults or value != defaults[name]}}


def _jsonable(value):
    """``value`` as JSON keeps it (what the manifest compares on a re-run): objects by repr."""
    return json.loads(json.dumps(value, default=repr))


def _write_manifest(path: Path, parts: list, format: str) -> None:
    """Rewrite the manifest whole (written beside and renamed, so a reader never sees half)."""
    partial = path.with_name(f".{path.name}.partial")
    partial.write_text(json.dumps({"format": format, "parts": parts}, indent=2) + "\n")
    os.replace(partial, path)


def _resume(parts: list, manifest: Path, format: str) -> None:
    """Mark ``skipped`` the parts an earlier run made: the manifest says done (or skipped) for the
    same source, file name and params, and the file is there and loads."""
    try:
        earlier = json.loads(manifest.read_text())
        recorded = {entry["name"]: entry for entry in earlier["parts"]} if earlier.get("format") == format else {}
    except (OSError, ValueError, KeyError, TypeError):
        return  # no manifest, or one this run cannot read: every part is packed
    for part in parts:
        entry = recorded.get(part["name"])
        if not isinstance(entry, dict) or entry.get("status") not in (DONE, SKIPPED):
            continue
        same_file = Path(str(entry.get("file"))).name == Path(part["file"]).name  # out/ given another way is alike
        if not same_file or any(entry.get(key) != part[key] for key in ("source", "params")):
            continue
        try:
            load(part["file"], format)
        except (NdpackError, OSError, ValueError):
            continue  # missing or broken: packed again
        part.update({key: entry.get(key) for key in ("spheres", "fill", "stop_reason", "seconds")},
                    status=SKIPPED, error=None)


class _Lazy(Mapping):
    """name -> Packing: those in memory, the others loaded from their files when first asked for."""

    def __init__(self, packings: dict, files: dict):
        self._packings, self._files = packings, files

    def __getitem__(self, name: str):
        if self._packings[name] is None:
            self._packings[name] = load(*self._files[name])
        return self._packings[name]

    def __iter__(self):
        return iter(self._packings)

    def __len__(self) -> int:
        return len(self._packings)

    def __repr__(self) -> str:
        return f"<{len(self)} packings: {', '.join(self._packings)}>"
