"""Experiments from a TOML file, TOML text, a dict or keyword overrides, validated by the engine's
own parser: the same rules and the same messages as `breccia run FILE --set section.key=value`."""
import json
import math
import os
import tomllib


def toml_value(value):
    """A Python value as a TOML literal (the right-hand side of an override)."""
    if hasattr(value, "item") and not isinstance(value, (list, tuple, dict)):
        value = value.item()  # numpy scalars
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, (str, os.PathLike)):
        return json.dumps(os.fspath(value))  # JSON's escapes are TOML basic-string escapes
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + " }"
    if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
        items = value.tolist() if hasattr(value, "tolist") else value
        return "[" + ", ".join(toml_value(v) for v in items) + "]"
    raise TypeError(f"{value!r} ({type(value).__name__}): not a TOML value "
                    "(allowed: bool, int, float, str, path, list, dict)")


def _flatten(prefix, tables, out):
    for key, value in tables.items():
        dotted = f"{prefix}.{key}" if prefix else str(key)
        if isinstance(value, dict):
            _flatten(dotted, value, out)
        else:
            try:
                out.append(f"{dotted}={toml_value(value)}")
            except TypeError as e:
                raise TypeError(f"'{dotted}' = {e}") from None


def overrides_of(overrides=None, sections=None):
    """'section.key=value' strings from a mapping {"section.key": value} (or a list of such
    strings) and from keyword sections {"section": {"key": value}}."""
    out = []
    if isinstance(overrides, dict):
        _flatten("", overrides, out)
    elif overrides is not None:
        if isinstance(overrides, str):
            raise TypeError("overrides: a dict {'section.key': value} or a list of "
                            "'section.key=value' strings, not one string")
        out.extend(str(o) for o in overrides)
    if sections:
        _flatten("", sections, out)
    return out


def _core():
    from . import _core
    return _core


class Experiment:
    """An experiment, validated and fully resolved.

        Experiment()                                   # the built-in default (calibrated Berea UCS)
        Experiment("examples/brazilian.toml")          # a file
        Experiment("ucs.toml", sample={"max_particles": 800}, engine={"seed": 7})
        Experiment(overrides={"test.kind": "brazilian"})
        Experiment.from_toml(text), Experiment.from_dict({"sample": {...}, "test": {...}})

    Keyword arguments are sections of the experiment file; `overrides` takes dotted keys. Bad
    input raises breccia.InputError (a ValueError) with the command line's message.
    """

    def __init__(self, path=None, *, overrides=None, **sections):
        ov = overrides_of(overrides, sections)
        if path is None:
            self._spec = _core().parse_experiment("", "built-in default", ov)
        else:
            self._spec = _core().load_experiment(os.fspath(path), ov)

    @classmethod
    def _wrap(cls, spec):
        e = cls.__new__(cls)
        e._spec = spec
        return e

    @classmethod
    def from_toml(cls, text, source="<toml text>", *, overrides=None, **sections):
        return cls._wrap(_core().parse_experiment(text, source, overrides_of(overrides, sections)))

    @classmethod
    def from_dict(cls, tables):
        """The default experiment with every key of `tables` ({"section": {"key": value}})."""
        return cls._wrap(_core().parse_experiment("", "built-in default", overrides_of(tables)))

    def with_(self, overrides=None, **sections):
        """A copy with some keys changed (the same keywords as the constructor)."""
        ov = overrides_of(overrides, sections)
        return Experiment._wrap(_core().parse_experiment(self.to_toml(), self.source, ov))

    def to_toml(self):
        """Every key, defaults included: the experiment.toml a run writes."""
        return self._spec.to_toml()

    def to_dict(self):
        return tomllib.loads(self.to_toml())

    def __getitem__(self, dotted_key):
        node = self.to_dict()
        for part in dotted_key.split("."):
            if not isinstance(node, dict) or part not in node:
                raise KeyError(dotted_key)
            node = node[part]
        return node

    source = property(lambda self: self._spec.source)
    name = property(lambda self: self._spec.name)
    seed = property(lambda self: self._spec.seed)
    dimension = property(lambda self: self._spec.dimension)
    test = property(lambda self: self._spec.test_kind)
    output_directory = property(lambda self: self._spec.output_directory)

    def __repr__(self):
        return (f"Experiment(name={self.name!r}, test={self.test!r}, "
                f"dimension={self.dimension}, seed={self.seed}, source={self.source!r})")
