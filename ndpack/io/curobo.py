"""cuRobo collision spheres (``curobo``, ``.yml`` ``.yaml``, or ``.json`` by name; 3-D).

``{"collision_spheres": {link: [{"center": [x, y, z], "radius": r}, ...]}}``: a packing is
written as one link (option ``link``, default ``body``). ``.yml`` and ``.yaml`` files are YAML
(PyYAML's ``safe_dump``, :func:`curobo_yaml`); ``.json`` is chosen by ``format="curobo"`` and
read back by :func:`~ndpack.io.load` from its content. Reading takes every link's spheres,
drops disabled ones (a negative radius), and finds ``collision_spheres`` nested in a whole
cuRobo robot configuration (under ``robot_cfg: kinematics:``). YAML is read with PyYAML's safe
loader without aliases, which can make a few hundred bytes expand to billions of entries.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np

from ..errors import NdpackError
from ..packing import Packing
from . import limits
from .limits import check_nesting, parse_json, printable
from .metadata import packing_from
from .registry import Format, register, require_dim

#: Suffixes of cuRobo YAML files (the rest of the curobo format's suffixes are JSON).
YAML_SUFFIXES = (".yml", ".yaml")


def _write_curobo(packing: Packing, path: Path, link: str = "body") -> None:
    """``{"collision_spheres": {link: [{"center": [x, y, z], "radius": r}, ...]}}``, a sphere a line,
    as JSON, or as YAML for a ``.yml`` or ``.yaml`` file (:func:`curobo_yaml`)."""
    require_dim(packing.dim, range(3, 4), "cuRobo's collision_spheres")
    if path.suffix.lower() in YAML_SUFFIXES:
        path.write_text(curobo_yaml({str(link): (packing.centers, packing.radii)}))
        return
    spheres = [
        json.dumps({"center": center, "radius": radius})
        for center, radius in zip(packing.centers.tolist(), packing.radii.tolist())
    ]
    body = ",\n".join(f"      {sphere}" for sphere in spheres)
    text = f'{{\n  "collision_spheres": {{\n    {json.dumps(str(link))}: [\n{body}\n    ]\n  }}\n}}\n'
    path.write_text(text if spheres else text.replace("[\n\n    ]", "[]"))


def curobo_yaml(links: dict, comment: str | None = None) -> str:
    """cuRobo's collision spheres file as YAML text (PyYAML's ``safe_dump``; every number reads
    back as the same float64)::

        collision_spheres:
          base_link:
          - center: [0.1, 0.0, 0.25]
            radius: 0.05

    Parameters
    ----------
    links : dict
        Link name -> ``(centers, radii)``: ``(n, 3)`` and ``(n,)`` arrays, in the link's frame.
    comment : str, optional
        Written first, as ``#`` comment lines.

    Returns
    -------
    str
    """
    import yaml

    document = {}
    for link, (centers, radii) in links.items():
        centers = np.asarray(centers, dtype=np.float64).reshape(-1, 3)
        radii = np.asarray(radii, dtype=np.float64).reshape(-1)
        if len(centers) != len(radii):
            raise NdpackError(f"link {link!r} has {len(centers)} centres but {len(radii)} radii")
        if not (np.isfinite(centers).all() and np.isfinite(radii).all()):
            raise NdpackError(f"cannot write link {link!r} in cuRobo's collision spheres: every number must be finite")
        document[str(link)] = [{"center": center, "radius": radius}
                               for center, radius in zip(centers.tolist(), radii.tolist())]
    lines = [f"# {line}".rstrip() for line in (comment.splitlines() if comment else [])]
    body = yaml.safe_dump({"collision_spheres": document}, sort_keys=False, default_flow_style=None)
    return "\n".join(lines + [body])


def curobo_packing(document: dict) -> Packing:
    """The spheres of every link of a document holding ``collision_spheres``, as one Packing
    (disabled spheres, of negative radius, dropped)."""
    links = document["collision_spheres"]
    if isinstance(links, str):
        raise ValueError(f"its collision_spheres names another file ({links!r}): load that file")
    if links is None:
        links = {}
    if not isinstance(links, dict):
        raise ValueError("its collision_spheres is not a mapping of link names to sphere lists")
    spheres = [sphere for link in links.values() for sphere in (link or [])]
    centers = np.array([sphere["center"] for sphere in spheres], dtype=np.float64).reshape(-1, 3)
    radii = np.array([sphere["radius"] for sphere in spheres], dtype=np.float64)
    keep = radii > 0  # cuRobo marks disabled spheres by a negative radius
    return packing_from(None, centers[keep], radii[keep])


def _read_curobo(path: Path) -> Packing:
    text = path.read_text()
    if path.suffix.lower() in YAML_SUFFIXES:
        document = _find_collision_spheres(_load_yaml(text))
        if document is None:
            raise ValueError("it has no 'collision_spheres' mapping")
        return curobo_packing(document)
    document = parse_json(text)
    if not isinstance(document, dict) or "collision_spheres" not in document:
        raise ValueError("it has no top-level 'collision_spheres'")
    return curobo_packing(document)


def _find_collision_spheres(document, depth: int = 0):
    """The mapping that holds ``collision_spheres``: the document, or one nested in it (a whole
    cuRobo robot configuration keeps it under ``robot_cfg: kinematics:``); None if none does."""
    if not isinstance(document, dict) or depth > 8:
        return None
    if "collision_spheres" in document:
        return document
    for value in document.values():
        found = _find_collision_spheres(value, depth + 1)
        if found is not None:
            return found
    return None


def _load_yaml(text: str):
    """A YAML document, read with PyYAML's safe loader without aliases (:func:`_no_alias_loader`)."""
    import yaml

    try:
        document = yaml.load(text, Loader=_no_alias_loader())  # a SafeLoader's subclass: safe, no aliases
    except yaml.YAMLError as error:
        raise ValueError(f"its YAML is not valid ({' '.join(str(error).split())})") from None
    except RecursionError:
        most = limits.MAX_NESTING
        raise ValueError(f"its YAML is nested too deep to read (ndpack reads at most {most} levels)") from None
    check_nesting(document, "YAML")
    return document


@functools.cache
def _no_alias_loader():
    """PyYAML's ``SafeLoader`` that refuses aliases (``*name``): an alias repeats a node, and a few
    hundred bytes of aliases to aliases (with ``<<:`` merges, which copy) expand to billions of
    entries. cuRobo's sphere files and ndpack's use none."""
    import yaml

    class NoAliasLoader(yaml.SafeLoader):
        def compose_node(self, parent, index):
            if self.check_event(yaml.AliasEvent):
                event = self.peek_event()
                alias = printable(event.anchor)
                raise ValueError(f"its line {event.start_mark.line + 1} uses the YAML alias *{alias}: ndpack reads "
                                 "YAML without aliases (a few of them can repeat a node billions of times)")
            return super().compose_node(parent, index)

    return NoAliasLoader


register(Format("curobo", (".json", ".yml", ".yaml"), "3", "spheres, as cuRobo collision_spheres (JSON or YAML)",
                {"link": "body"}, _write_curobo, _read_curobo), default_for=YAML_SUFFIXES)
