"""The typed, documented API: the native module's stubs (_gripopt.pyi) name exactly what
the module has, with its parameters; every public item of the package has a docstring."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import gripopt
import gripopt.dask
import gripopt.pymoo
from gripopt import _gripopt

STUBS = Path(gripopt.__file__).with_name("_gripopt.pyi")


def public(names) -> set[str]:
    return {n for n in names if not n.startswith("_")}


def stub_items() -> tuple[set[str], dict[str, dict[str, ast.AST]], dict[str, ast.AST]]:
    """The stubs' public module-level names, their classes' members and functions."""
    tree = ast.parse(STUBS.read_text())
    names: set[str] = set()
    classes: dict[str, dict[str, ast.AST]] = {}
    functions: dict[str, ast.AST] = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            classes[node.name] = {m.name: m for m in node.body if isinstance(m, ast.FunctionDef)}
            names.add(node.name)
        elif isinstance(node, ast.FunctionDef):
            functions[node.name] = node
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return public(names), classes, functions


def params(fn: ast.FunctionDef) -> list[str]:
    a = fn.args
    return [p.arg for p in [*a.posonlyargs, *a.args, *a.kwonlyargs] if p.arg != "self"]


def check_signature(obj, fn: ast.FunctionDef, where: str) -> None:
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return  # a property or a built-in without a text signature
    got = [p for p in sig.parameters if p != "self"]
    assert got == params(fn), f"{where}: stubs say {params(fn)}, the module {got}"


def test_the_stubs_are_the_native_module():
    names, classes, functions = stub_items()
    declared_types = {"Column", "ColumnInfo"}  # aliases the stubs define for themselves
    assert public(dir(_gripopt)) == public(names) - declared_types
    for cls, members in classes.items():
        native = getattr(_gripopt, cls)
        assert public(dir(native)) == public(members), cls
        for name, fn in members.items():
            if not name.startswith("_"):
                check_signature(getattr(native, name), fn, f"{cls}.{name}")
    for name, fn in functions.items():
        check_signature(getattr(_gripopt, name), fn, name)


def test_every_public_item_is_documented():
    undocumented = []
    for module in (gripopt, gripopt.pymoo, gripopt.dask):
        assert module.__doc__, module.__name__
        for name in getattr(module, "__all__", public(vars(module))):
            obj = getattr(module, name)
            if not (inspect.isclass(obj) or inspect.isfunction(obj)) or not obj.__module__.startswith("gripopt"):
                continue
            if not inspect.getdoc(obj):
                undocumented.append(f"{module.__name__}.{name}")
            if inspect.isclass(obj):
                for m, member in vars(obj).items():
                    if m.startswith("_") or not (inspect.isfunction(member) or isinstance(member, (property, classmethod, staticmethod))):
                        continue
                    if not inspect.getdoc(member):
                        undocumented.append(f"{module.__name__}.{name}.{m}")
    assert not undocumented, undocumented
