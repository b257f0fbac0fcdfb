"""The public surface: every name in ``planner.__all__`` resolves, and every wing is reachable from it."""

import importlib
import inspect

import pytest

import planner


@pytest.mark.parametrize("name", planner.__all__)
def test_every_exported_name_resolves(name: str) -> None:
    assert getattr(planner, name) is not None


def test_exports_are_the_objects_of_their_modules() -> None:
    for name, module in planner._EXPORTS.items():
        assert getattr(planner, name) is getattr(importlib.import_module(module), name), name


def test_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no_such_thing"):
        planner.no_such_thing  # noqa: B018


def test_every_error_type_is_exported() -> None:
    errors = importlib.import_module("planner.errors")
    defined = {n for n, obj in inspect.getmembers(errors, inspect.isclass) if obj.__module__ == errors.__name__}
    assert defined <= set(planner.__all__), defined - set(planner.__all__)


def test_version_is_a_string() -> None:
    assert isinstance(planner.__version__, str) and planner.__version__
