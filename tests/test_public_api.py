"""The public API stays typed: every function and public method that ``import ndpack as nd`` offers
says what it returns, so that mypy (CI, ``[tool.mypy]`` in pyproject.toml) can check users' code
against it (tests/typing/public_api.py)."""

import inspect

import ndpack as nd


def _public_callables():
    for name in nd.__all__:
        obj = getattr(nd, name)
        if inspect.isfunction(obj):
            yield name, obj
        elif inspect.isclass(obj):
            for attribute, member in vars(obj).items():
                if not attribute.startswith("_") and inspect.isfunction(member):
                    yield f"{name}.{attribute}", member


def test_every_public_function_and_method_says_what_it_returns():
    found = dict(_public_callables())
    assert {"pack", "Packing.verify", "cover", "Covering.tree"} <= set(found)
    missing = [name for name, function in found.items()
               if inspect.signature(function).return_annotation is inspect.Signature.empty]
    assert not missing, f"public callables without a return annotation: {missing}"
