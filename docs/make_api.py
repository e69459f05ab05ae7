"""Write docs/api.md, the API reference, from the docstrings of ndpack's public names.

    python docs/make_api.py                 # rewrites docs/api.md
    python docs/make_api.py -o /tmp/api.md  # somewhere else (the test compares the two)

What it documents: every name in ``ndpack.__all__``; ``ndpack.backends.available``, ``use``,
``get_backend`` and ``names``; and the public functions and classes of ``ndpack.io`` and
``ndpack.pictures``. Signatures come from ``inspect.signature``, docstrings
are copied as they are (in text blocks, so their layout survives). A class lists the public
methods and properties it defines itself (not those it inherits; ``Oracle`` has those).
"""

from __future__ import annotations

import argparse
import inspect
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the checkout's ndpack, even when another is installed

import ndpack  # noqa: E402
import ndpack.backends  # noqa: E402
import ndpack.io  # noqa: E402
import ndpack.pictures  # noqa: E402
import ndpack.drivers.collision.sphere_tree  # noqa: E402
import ndpack.drivers.collision.robots  # noqa: E402

#: The top-level names by topic, in this order; a name of ``ndpack.__all__`` missing here goes
#: to "Other", so that nothing public is left out.
TOPICS = {
    "Packing": ["pack", "Packing", "RoundStats", "verify", "Verification"],
    "Coverings (collision spheres)": ["cover", "Covering", "CoverReport", "check_covering"],
    "The oracle protocol": ["Oracle", "Volume", "ball_volume"],
    "Shapes": ["Ball", "Box", "RoundedBox", "HalfSpace", "Slab", "Capsule", "Cylinder", "ConvexPolytope",
               "Simplex", "Ellipsoid", "Torus", "Polygon", "TriangleMesh", "rotation"],
    "CSG": ["Union", "Intersection", "Difference", "Complement", "Translate", "Rotate", "Scale", "Offset",
            "Shell", "SmoothUnion"],
    "Plug-ins": ["Function", "plugin", "ScalarFunction", "scalar_plugin"],
    "Errors and warnings": ["NdpackError", "ShapeError", "DimensionError", "BoundsError", "OracleError",
                            "ParameterError", "BackendError", "KernelError", "MeshWarning"],
}
BACKEND_FUNCTIONS = ["available", "use", "get_backend", "names"]
MODULES = [ndpack.io, ndpack.pictures, ndpack.drivers.collision.sphere_tree, ndpack.drivers.collision.robots]


class _Text:
    """An annotation shown as written: ``from __future__ import annotations`` leaves strings,
    which ``inspect`` would print in quotes."""

    def __init__(self, text):
        self.text = text

    def __repr__(self):
        return self.text


def signature(obj, method: bool = False) -> str:
    """``(a, b=1) -> c`` of a function, or of a class's constructor (no return type); ``""`` where
    none is readable. ``method``: leave out ``self`` or ``cls``."""
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return ""
    plain = lambda annotation: _Text(annotation) if isinstance(annotation, str) else annotation  # noqa: E731
    parameters = [p.replace(annotation=plain(p.annotation)) for p in sig.parameters.values()]
    if method and parameters and parameters[0].name in ("self", "cls"):
        parameters = parameters[1:]
    returns = inspect.Signature.empty if inspect.isclass(obj) else plain(sig.return_annotation)
    return str(sig.replace(parameters=parameters, return_annotation=returns))


def docstring(obj) -> str:
    doc = inspect.getdoc(obj)
    if not doc:
        return "*No docstring.*\n"
    return "```text\n" + doc.replace("```", "'''") + "\n```\n"


def anchor(name: str) -> str:
    return name.replace(".", "-").lower()


def members(cls) -> list[tuple[str, object]]:
    """Public methods, class methods and properties that ``cls`` defines itself, in source order."""
    found = []
    for name, value in vars(cls).items():
        if name.startswith("_"):
            continue
        if isinstance(value, (staticmethod, classmethod)):
            value = value.__func__
        if inspect.isfunction(value) or isinstance(value, property):
            found.append((name, value))
    return found


def entry(qualified: str, obj, level: int = 3) -> list[str]:
    """The markdown of one function or class."""
    hashes = "#" * level
    lines = [f'<a id="{anchor(qualified)}"></a>', ""]
    if inspect.isclass(obj):
        kind = "exception" if issubclass(obj, BaseException) else "class"
        bases = [base.__name__ for base in obj.__bases__ if base is not object and not base.__name__.startswith("_")]
        based = f"({', '.join(bases)})" if bases else ""
        shown = "" if issubclass(obj, BaseException) else signature(obj)
        lines += [f"{hashes} {kind} `{qualified}{shown}`", ""]
        if based:
            lines += [f"Subclass of {', '.join(f'`{base}`' for base in bases)}.", ""]
        lines.append(docstring(obj))
        for name, member in members(obj):
            if isinstance(member, property):
                lines += [f"- **`{name}`** (property)", ""]
                doc = inspect.getdoc(member)
                if doc:
                    lines += ["  " + line if line else "" for line in docstring(member).splitlines()] + [""]
            else:
                lines += [f"- **`{name}{signature(member, method=True)}`**", ""]
                lines += ["  " + line if line else "" for line in docstring(member).splitlines()] + [""]
    else:
        lines += [f"{hashes} `{qualified}{signature(obj)}`", "", docstring(obj)]
    return lines


def module_names(module) -> list[str]:
    """Public functions and classes defined in ``module``, in source order; for a package, those
    of its ``__all__`` (defined in its modules), in that order."""
    if hasattr(module, "__path__") and hasattr(module, "__all__"):
        return [name for name in module.__all__
                if inspect.isfunction(getattr(module, name)) or inspect.isclass(getattr(module, name))]
    names = []
    for name, value in vars(module).items():
        if name.startswith("_") or not (inspect.isfunction(value) or inspect.isclass(value)):
            continue
        if value.__module__ == module.__name__:
            names.append(name)
    return names


def build() -> str:
    listed = [name for names in TOPICS.values() for name in names]
    topics = dict(TOPICS)
    others = [name for name in ndpack.__all__ if name not in listed]
    if others:
        topics["Other"] = others
    missing = [name for name in listed if name not in ndpack.__all__]
    if missing:
        raise SystemExit(f"make_api.py lists names that ndpack.__all__ no longer has: {', '.join(missing)}")

    lines = [
        "# API reference",
        "",
        "Generated by `python docs/make_api.py` from the docstrings of ndpack "
        f"{ndpack.__version__}; do not edit it by hand. Everything below `ndpack` is imported with",
        "`import ndpack as nd`; the modules `ndpack.backends`, `ndpack.io` and `ndpack.pictures`",
        "are imported by name (`import ndpack.pictures`).",
        "",
        "## Contents",
        "",
    ]
    for topic, names in topics.items():
        links = ", ".join(f"[`{name}`](#{anchor('ndpack.' + name)})" for name in names)
        lines.append(f"- {topic}: {links}")
    backend_links = ", ".join(f"[`{name}`](#{anchor('ndpack.backends.' + name)})" for name in BACKEND_FUNCTIONS)
    lines.append(f"- [`ndpack.backends`](#ndpack-backends): {backend_links}")
    for module in MODULES:
        links = ", ".join(f"[`{name}`](#{anchor(module.__name__ + '.' + name)})" for name in module_names(module))
        lines.append(f"- [`{module.__name__}`](#{anchor(module.__name__)}): {links}")
    lines.append("")

    for topic, names in topics.items():
        lines += [f"## {topic}", ""]
        for name in names:
            lines += entry(f"ndpack.{name}", getattr(ndpack, name))

    lines += ['<a id="ndpack-backends"></a>', "", "## `ndpack.backends`", "", docstring(ndpack.backends)]
    for name in BACKEND_FUNCTIONS:
        lines += entry(f"ndpack.backends.{name}", getattr(ndpack.backends, name))

    for module in MODULES:
        lines += [f'<a id="{anchor(module.__name__)}"></a>', "", f"## `{module.__name__}`", "", docstring(module)]
        for name in module_names(module):
            lines += entry(f"{module.__name__}.{name}", getattr(module, name))

    text = "\n".join(lines)
    while "\n\n\n" in text:
        text = text.replace("\n\n\n", "\n\n")
    return text.rstrip("\n") + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-o", "--output", default=str(HERE / "api.md"), help="where to write (default docs/api.md)")
    args = parser.parse_args(argv)
    Path(args.output).write_text(build())
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
