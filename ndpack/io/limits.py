"""What a file may make ndpack do: the bounds every loader checks before it allocates or recurses.

A packing file may come from anyone, and a few bytes can declare billions of spheres, a
dimension of a billion, an archive that inflates a thousandfold or a document nested past
Python's stack. The loaders check what a file declares against what it can hold (its size on
disk) and against the limits below before they allocate, parse or build anything from it, and
refuse in one line what does not fit. The limits are module constants: a program that needs
larger files may raise them (``ndpack.io.limits.MAX_DIM = 512``) before loading.
"""

from __future__ import annotations

import json

#: The largest dimension a file may declare. ndpack's grid packs at most 22-D (``MAX_CELLS``
#: cells, at least 2 an axis); 256 leaves room for packings made elsewhere while keeping every
#: array sized by the dimension (a simplex's facets, a picture's projection) small. A file that
#: says ``dim: 1000000000`` is refused before anything is sized by it.
MAX_DIM = 256

#: The deepest nesting of lists and mappings in a file's JSON or YAML. ndpack's metadata nests 3
#: deep and a cuRobo robot configuration about 6; deeper documents exhaust Python's stack in the
#: parser or in whatever walks them later (printing, saving).
MAX_NESTING = 64

#: A ``.npz`` archive may unpack to at most ``max(NPZ_FREE_BYTES, NPZ_MAX_RATIO * its size)``.
#: Packings compress 1.1x to 3x (float64 centres barely compress), while a zip bomb of zeros
#: inflates about 1000x: a 2 MB bomb is refused from its directory, before a byte is inflated.
NPZ_MAX_RATIO = 100
#: Archives may unpack to this much whatever their ratio (a small packing of identical spheres
#: compresses well, and 64 MiB costs a fraction of a second).
NPZ_FREE_BYTES = 64 << 20


def parse_json(text: str):
    """``json.loads(text)``, with a document nested past Python's stack refused as a ValueError
    starting "it" (the metadata's own nesting is checked by :func:`check_nesting`)."""
    try:
        return json.loads(text)
    except RecursionError:
        raise ValueError(f"its JSON is nested too deep to read (ndpack reads at most {MAX_NESTING} levels)") from None


def check_nesting(document, language: str) -> None:
    """Refuse ``document`` (parsed JSON or YAML) nested more than :data:`MAX_NESTING` deep."""
    level, current = 0, [document]
    while current:
        level += 1
        if level > MAX_NESTING:
            raise ValueError(f"its {language} is nested more than {MAX_NESTING} levels deep")
        following = []
        for value in current:
            if isinstance(value, dict):
                following.extend(value.values())
            elif isinstance(value, (list, tuple)):
                following.extend(value)
        current = [value for value in following if isinstance(value, (dict, list, tuple))]


def check_count(count: int, what: str, most: int, room: str) -> None:
    """Refuse a declared ``count`` of ``what`` (``"vertices"``) larger than the ``most`` that the
    file's ``room`` (``"its 80 bytes of data"``) can hold, or negative: before anything is sized by it."""
    if count < 0:
        raise ValueError(f"it declares {count} {what}")
    if count > most:
        raise ValueError(f"it declares {count:,} {what}, but {room} hold at most {most:,}")


def check_dim(dim, what: str = "its dimension") -> int:
    """``dim`` if it is a whole number from 1 to :data:`MAX_DIM`; a ValueError starting "it" otherwise."""
    if isinstance(dim, bool) or not isinstance(dim, int) or dim < 1:
        raise ValueError(f"{what} {shown(dim)} is not a positive integer")
    if dim > MAX_DIM:
        raise ValueError(f"{what} {dim:,} is more than ndpack reads (at most {MAX_DIM}, ndpack.io.limits.MAX_DIM)")
    return dim


def printable(text) -> str:
    """``text`` with every character that is not printable (terminal escapes, newlines, bidi
    controls) written as Python writes it in a string's repr (``\\x1b``, ``\\n``, ``\\u202e``):
    what ndpack prints from a file is shown, never obeyed by the terminal."""
    text = str(text)
    if text.isprintable():
        return text
    return "".join(char if char.isprintable() else repr(char)[1:-1] for char in text)


def shown(value, width: int = 60) -> str:
    """``repr(value)``, printable and cut to about ``width`` characters: a file's value in a message."""
    text = printable(repr(value))
    return text if len(text) <= width else text[: width - 3] + "..."
