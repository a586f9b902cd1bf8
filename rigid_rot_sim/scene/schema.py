"""JSON Schema for the input files, and its errors as one line naming the file and the key.

Each input file type (scene, sweep spec) is described by one declarative JSON Schema, a
plain dict built with the helpers below and exported to ``config/schema/*.schema.json``
for editors. :func:`check` validates parsed YAML against it and raises the first problem
as one line, e.g. ``scene.yaml: body.inertia_tensor[1][2]: must be of magnitude <= 1e+12,
got 1e+300``. What a schema cannot say (a physical inertia, names from a registry, ROS
names, rules across sections) is checked after it by small functions of each loader.

The validator is jsonschema's Draft 2020-12 one (jsonschema >= 4.0: the PyPI releases and
Ubuntu Noble's python3-jsonschema 4.10), with the ``number`` type as strict as JSON itself:
YAML also has ``.nan`` and ``.inf``, which are refused, and an ``integer`` must be
written as one (``2.0`` is a number, not an integer). Integers too large for a float stay
numbers and are refused by the bounds every number of a schema has.

A subschema may carry ``errorMessage`` (the editors' convention, e.g. VS Code's JSON
language service): it replaces the generated message when that subschema fails as a whole.

>>> spec = mapping("A box.", {"side": number("Side, m.", exclusive_minimum=0.0)}, required=["side"])
>>> check({"side": -1.0}, spec, "box.yaml", ValueError)
Traceback (most recent call last):
...
ValueError: box.yaml: side: must be > 0, got -1
>>> check({"size": 1.0}, spec, "box.yaml", ValueError)
Traceback (most recent call last):
...
ValueError: box.yaml: size: unknown key (allowed: side)
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, TypeVar

from jsonschema import Draft202012Validator, validators
from jsonschema.exceptions import ValidationError

from rigid_rot_sim.core import limits

__all__ = [
    "DIALECT",
    "check",
    "validated",
    "dump",
    "number",
    "magnitude",
    "integer",
    "text",
    "vector",
    "array",
    "choice",
    "mapping",
    "nullable",
    "iter_schemas",
]

DIALECT = "https://json-schema.org/draft/2020-12/schema"


# ----------------------------------------------------------------------------- building


def number(
    description: str,
    *,
    minimum: float | None = None,
    exclusive_minimum: float | None = None,
    maximum: float = limits.MAX_MAGNITUDE,
    default: float | None = None,
) -> dict[str, Any]:
    """A finite number up to ``maximum``; at least ``minimum`` (or above ``exclusive_minimum``),
    else at least ``-maximum`` (a bound on its magnitude)."""
    schema: dict[str, Any] = {"description": description, "type": "number"}
    if exclusive_minimum is not None:
        schema["exclusiveMinimum"] = exclusive_minimum
    else:
        schema["minimum"] = -maximum if minimum is None else minimum
    schema["maximum"] = maximum
    if default is not None:
        schema["default"] = default
    return schema


def magnitude(description: str) -> dict[str, Any]:
    """A physical number: finite, of magnitude at most MAX_MAGNITUDE."""
    return number(description)


def integer(
    description: str, *, minimum: int, maximum: int | None = None, default: int | None = None
) -> dict[str, Any]:
    schema: dict[str, Any] = {"description": description, "type": "integer", "minimum": minimum}
    if maximum is not None:
        schema["maximum"] = maximum
    if default is not None:
        schema["default"] = default
    return schema


def text(description: str, max_length: int = limits.MAX_NAME_LENGTH, default: str | None = None) -> dict[str, Any]:
    """A string with a non-blank character, at most ``max_length`` characters."""
    schema: dict[str, Any] = {"description": description, "type": "string", "pattern": r"\S", "maxLength": max_length}
    if default is not None:
        schema["default"] = default
    return schema


def vector(description: str, size: int, item: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """A list of exactly ``size`` items (physical numbers unless ``item`` says otherwise)."""
    return array(description, item if item is not None else magnitude("component"), min_items=size, max_items=size)


def array(
    description: str, item: Mapping[str, Any], *, min_items: int = 0, max_items: int | None = None
) -> dict[str, Any]:
    schema: dict[str, Any] = {"description": description, "type": "array", "items": dict(item)}
    if min_items:
        schema["minItems"] = min_items
    if max_items is not None:
        schema["maxItems"] = max_items
    return schema


def choice(description: str, values: Sequence[str], default: str | None = None) -> dict[str, Any]:
    """One of the strings ``values``."""
    schema: dict[str, Any] = {"description": description, "enum": list(values)}
    if default is not None:
        schema["default"] = default
    return schema


def mapping(
    description: str, properties: Mapping[str, Mapping[str, Any]], *, required: Iterable[str] = (), **rules: Any
) -> dict[str, Any]:
    """A mapping with exactly these keys allowed; ``rules`` are further keywords (oneOf, not, ...).

    Keyword order is error priority: a wrong type first, then an unknown key, a missing key,
    the ``rules``, and the values in the order of ``properties``.
    """
    schema: dict[str, Any] = {"description": description, "type": "object", "additionalProperties": False}
    required = list(required)
    if required:
        schema["required"] = required
    schema.update(rules)
    schema["properties"] = {name: dict(value) for name, value in properties.items()}
    return schema


def nullable(schema: Mapping[str, Any]) -> dict[str, Any]:
    """``schema``, or null (YAML ``~``, or a key written without a value) for "the default"."""
    result = dict(schema)
    kind = result.get("type")
    if isinstance(kind, str):
        result["type"] = [kind, "null"]
        return result
    description = result.pop("description", "")
    return {"description": description, "anyOf": [{"type": "null"}, result]}


def dump(schema: Mapping[str, Any]) -> str:
    """The schema as the JSON text of ``config/schema/*.schema.json``."""
    return json.dumps(schema, indent=2, ensure_ascii=False) + "\n"


def iter_schemas(schema: Any) -> Iterable[dict[str, Any]]:
    """Every subschema of ``schema`` (itself included), depth first."""
    if isinstance(schema, dict):
        yield schema
        for key, value in schema.items():
            if key in ("properties", "$defs"):
                for sub in value.values():
                    yield from iter_schemas(sub)
            elif key in ("items", "additionalProperties", "not", "if", "then", "else"):
                yield from iter_schemas(value)
            elif key in ("anyOf", "oneOf", "allOf"):
                for sub in value:
                    yield from iter_schemas(sub)


# ----------------------------------------------------------------------------- checking


def _is_number(checker: Any, instance: Any) -> bool:
    if isinstance(instance, bool) or not isinstance(instance, (int, float)):
        return False
    return isinstance(instance, int) or math.isfinite(instance)


def _is_integer(checker: Any, instance: Any) -> bool:
    return isinstance(instance, int) and not isinstance(instance, bool)


_Validator = validators.extend(
    Draft202012Validator,
    type_checker=Draft202012Validator.TYPE_CHECKER.redefine_many({"number": _is_number, "integer": _is_integer}),
)


_VALIDATORS: dict[int, tuple[Mapping[str, Any], Any]] = {}


def _validator(schema: Mapping[str, Any]) -> Any:
    """The validator of ``schema`` (the module-level schema constants), built once."""
    cached = _VALIDATORS.get(id(schema))
    if cached is None or cached[0] is not schema:
        cached = _VALIDATORS[id(schema)] = (schema, _Validator(schema))
    return cached[1]


def check(data: Any, schema: Mapping[str, Any], label: str, error_class: type[ValueError]) -> None:
    """Validate ``data`` against ``schema``; the first problem is raised as
    ``error_class("<label>: <key path>: <problem>")``."""
    validator = _validator(schema)
    error = next(iter(validator.iter_errors(data)), None)
    if error is None:
        return
    path, problem = _explain(_focus(error))
    where = _key_path(data, path)
    raise error_class(f"{label}: {where}: {problem}" if where else f"{label}: {problem}")


T = TypeVar("T")


def validated(
    data: Any, schema: Mapping[str, Any], source: str, error_class: type[ValueError], build: Callable[[Any], T]
) -> T:
    """``build(data)`` once ``data`` passed ``schema``: the loaders' one path from parsed YAML to
    their dataclasses. A schema problem, or a ValueError of ``build`` (``"<key>: <problem>"``),
    is raised as one ``error_class`` line starting with the file name of ``source``."""
    label = os.path.basename(source) if source else "<string>"
    check(data, schema, label, error_class)
    try:
        return build(data)
    except ValueError as exc:
        raise error_class(f"{label}: {exc}") from None


def _loose_type(kind: str, instance: Any) -> bool:
    """Whether ``instance`` is of JSON type ``kind``, nan, inf and huge integers counting as numbers."""
    if kind in ("number", "integer"):
        return (
            isinstance(instance, (int, float))
            and not isinstance(instance, bool)
            and (kind == "number" or isinstance(instance, int))
        )
    python = {"string": str, "object": dict, "array": list, "boolean": bool, "null": type(None)}[kind]
    return isinstance(instance, python)


def _fits(branch: Mapping[str, Any], instance: Any) -> bool:
    """Whether ``instance`` is of the kind ``branch`` describes (a mistake inside it is its own)."""
    if "const" in branch:
        return type(branch["const"]) is type(instance)
    if "enum" in branch:
        return any(type(value) is type(instance) for value in branch["enum"])
    kinds = branch.get("type")
    if kinds is None:
        return True
    return any(_loose_type(kind, instance) for kind in ([kinds] if isinstance(kinds, str) else kinds))


def _keys_alternatives(branches: Sequence[Mapping[str, Any]]) -> list[str] | None:
    """The key names when each branch is ``{"required": [name]}`` (exactly one of these keys)."""
    names = [branch.get("required") for branch in branches]
    pairs = zip(branches, names, strict=True)
    if all(len(branch) == 1 and isinstance(name, list) and len(name) == 1 for branch, name in pairs):
        return [name[0] for name in names]  # type: ignore[index]
    return None


def _focus(error: ValidationError) -> ValidationError:
    """The error to report: inside anyOf/oneOf, the mistake of the one branch the value is meant for."""
    while error.validator in ("anyOf", "oneOf"):
        if error.validator == "oneOf" and _keys_alternatives(error.validator_value) is not None:
            return error
        fitting = [i for i, branch in enumerate(error.validator_value) if _fits(branch, error.instance)]
        if len(fitting) != 1:
            return error
        inner = [e for e in error.context or () if e.relative_schema_path[0] == fitting[0]]
        if not inner or ("errorMessage" in error.schema and inner[0].absolute_path == error.absolute_path):
            return error  # the value itself is wrong: the message written for it says best how
        error = inner[0]
    return error


def _show(value: Any) -> str:
    """A value as echoed in an error message: its repr, cut to a readable length."""
    return limits.clip_text(repr(value), 60)


def _describe(schema: Mapping[str, Any]) -> str:
    """What a value of ``schema`` is, in words: "a list of 3 numbers", "'hold' or a mapping"."""
    if "errorMessage" in schema:
        return str(schema["errorMessage"]).removeprefix("must be ")
    if "const" in schema:
        return repr(schema["const"])
    if "enum" in schema:
        values = [str(v) for v in schema["enum"]]
        return f"one of {', '.join(values)}"
    kinds = schema.get("type", [])
    if kinds:
        words = [_describe_type(kind, schema) for kind in ([kinds] if isinstance(kinds, str) else kinds)]
    else:
        branches = schema.get("anyOf", schema.get("oneOf", []))
        words = list(dict.fromkeys(_describe(branch) for branch in branches))
    if not words:
        return "a value"
    return " or ".join([", ".join(words[:-1]), words[-1]]) if len(words) > 1 else words[0]


def _describe_type(kind: str, schema: Mapping[str, Any]) -> str:
    if kind == "array":
        item = _plural(_describe(schema.get("items", {})))
        count = schema.get("minItems")
        if count is not None and count == schema.get("maxItems"):
            return f"a list of {count} {item}"
        return f"a non-empty list of {item}" if count else f"a list of {item}"
    if kind == "string":
        return "a non-empty string" if schema.get("pattern") == r"\S" or schema.get("minLength") else "a string"
    return {
        "number": "a number",
        "integer": "an integer",
        "object": "a mapping",
        "boolean": "a boolean",
        "null": "null",
    }[kind]


def _plural(words: str) -> str:
    for single, plural in (
        ("a list of", "lists of"),
        ("a non-empty list of", "non-empty lists of"),
        ("a non-empty string", "non-empty strings"),
        ("a number", "numbers"),
        ("an integer", "integers"),
        ("a mapping", "mappings"),
        ("a string", "strings"),
    ):
        if words.startswith(single):
            return plural + words[len(single) :]
    return words


def _hint(description: str | None) -> str:
    """A short description, in parentheses, to say what a missing key is."""
    text = (description or "").rstrip(".")
    if text[1:2].islower():  # a capitalised word, not a unit or an acronym
        text = text[:1].lower() + text[1:]
    return f" ({text})" if text and len(text) <= 80 else ""


def _explain(error: ValidationError) -> tuple[list[Any], str]:
    """(key path, problem) of one jsonschema error, in the words of the loaders' messages."""
    path = list(error.absolute_path)
    schema, instance, kind, value = error.schema, error.instance, error.validator, error.validator_value
    if kind == "additionalProperties":
        allowed = list(schema.get("properties", {}))
        extra = next(name for name in instance if name not in allowed)
        return [*path, extra], f"unknown key (allowed: {', '.join(allowed)})"
    if kind == "required":
        missing = next(name for name in value if name not in instance)
        hint = _hint(schema.get("properties", {}).get(missing, {}).get("description"))
        return (path, f"needs {missing}{hint}") if path else ([missing], f"missing{hint}")
    if kind == "oneOf" and (keys := _keys_alternatives(value)) is not None:
        given = [name for name in keys if name in instance]
        return path, f"must give exactly one of {', '.join(keys)}, got {given or 'none'}"
    if kind == "not" and set(value) <= {"type", "required"} and "required" in value:
        return path, f"give {' or '.join(value['required'])}, not both"
    if "errorMessage" in schema:
        return path, f"{schema['errorMessage']}, got {_show(instance)}"
    if isinstance(instance, float) and not math.isfinite(instance):
        return path, f"must be finite, got {instance}"
    if isinstance(instance, int) and not isinstance(instance, bool) and schema.get("type") != "integer":
        try:
            float(instance)
        except OverflowError:  # a YAML integer too large for a float
            bound = schema.get("maximum", limits.MAX_MAGNITUDE)
            return (
                path,
                f"must be a number of magnitude <= {bound:g}, got an integer of {len(str(abs(instance)))} digits",
            )
    if schema.get("type") == "integer" and "maximum" in schema:
        return path, f"must be an integer from {schema['minimum']} to {schema['maximum']}, got {_show(instance)}"
    if kind in ("minimum", "maximum") and schema.get("minimum") == -schema.get("maximum", math.nan):
        return path, f"must be of magnitude <= {schema['maximum']:g}, got {instance:g}"
    comparisons = {"minimum": ">=", "maximum": "<=", "exclusiveMinimum": ">", "exclusiveMaximum": "<"}
    if kind in comparisons:
        return path, f"must be {comparisons[kind]} {value:g}, got {instance:g}"
    if kind == "maxItems" and schema.get("minItems") != value:
        return path, f"more than {value} items (limit), got {len(instance)}"
    if kind == "maxLength":
        return path, f"longer than {value} characters (limit)"
    if kind == "enum":
        return path, f"must be one of {', '.join(str(v) for v in value)}, got {_show(instance)}"
    if kind == "const":
        return path, f"must be {value!r}, got {_show(instance)}"
    if kind in ("type", "anyOf", "oneOf", "pattern", "minLength", "minItems", "maxItems"):
        return path, f"must be {_describe(schema)}, got {_show(instance)}"
    return path, limits.one_line(error.message)


def _key_path(data: Any, path: Sequence[Any]) -> str:
    """``path`` in the loaders' notation: ``body.inertia_tensor[1][2]``, ``torque_inputs[0].topic``."""
    parts: list[str] = []
    node = data
    for step in path:
        if isinstance(node, list):
            parts.append(f"[{step}]")
        else:
            name = limits.clip_text(" ".join(str(step).split()), 60)
            parts.append(f".{name}" if parts else name)
        try:
            node = node[step]
        except (KeyError, IndexError, TypeError):
            node = None
    return "".join(parts)
