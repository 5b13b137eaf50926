"""The typed, documented API: the native module's stubs (_gripopt.pyi) name exactly what
the module has, with its parameters, and type a recorded design's record as the schema the
library publishes says; every public item of the package has a docstring."""

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
    # aliases and record types the stubs define for themselves
    declared_types = {"Column", "ColumnInfo", "ObjectiveInfo", "Window", "Objectives", "DesignRecord"}
    assert public(dir(_gripopt)) == public(names) - declared_types
    for cls, members in classes.items():
        if cls in declared_types:
            continue
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


def stub_record(name: str) -> dict[str, str]:
    """The fields of the stubs' TypedDict `name`: {key: its annotation's source}."""
    tree = ast.parse(STUBS.read_text())
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == name)
    return {
        f.target.id: ast.unparse(f.annotation)
        for f in cls.body
        if isinstance(f, ast.AnnAssign) and isinstance(f.target, ast.Name)
    }


def test_the_design_record_follows_the_published_schema():
    """Origin: issue 39 item 3 (records as Python objects, stubs from the library's schema).
    DesignRecord's keys are the `/designs` schema's properties; a required key holds a value
    of the schema's type, any other may be None (or, `robust`, be absent); Objectives' keys
    are the objectives' table, which the schema lists too."""
    schema = _gripopt.DESIGN_SCHEMA
    fields = stub_record("DesignRecord")
    assert set(fields) == set(schema["properties"])
    scalar = {"integer": "int", "number": "float", "string": "str", "boolean": "bool"}
    for key, annotation in fields.items():
        kind = schema["properties"][key]["type"]
        if key in schema["required"]:
            assert not annotation.startswith(("Optional", "NotRequired")), key
            if kind in scalar:
                assert annotation == scalar[kind], (key, annotation)
        else:
            assert annotation.startswith(("Optional[", "NotRequired[")), key
            if kind in scalar:
                assert annotation == f"Optional[{scalar[kind]}]", (key, annotation)
    names = [o[0] for o in _gripopt.OBJECTIVES]
    assert list(stub_record("Objectives")) == names
    assert sorted(schema["properties"]["objectives"]["properties"]) == sorted(names)
    assert list(gripopt.pymoo.OBJECTIVES) == [("-" if o[3] == "maximise" else "") + o[0] for o in _gripopt.OBJECTIVES]


def test_a_recorded_design_is_python_objects(cli_run):
    """Origin: issue 39 item 3. A recorded design's record is a dict with the keys the
    schema lists, values not computed None (as the CLI's JSON writes them), not JSON text."""
    run = gripopt.Run(cli_run)
    rec = run.design(int(run.population["id"].iloc[0])).record
    assert isinstance(rec, dict) and isinstance(rec["objectives"], dict)
    assert set(rec) <= set(_gripopt.DESIGN_SCHEMA["properties"])
    assert set(_gripopt.DESIGN_SCHEMA["required"]) <= set(rec)
    assert isinstance(run.info, dict) and run.info["run_id"]
