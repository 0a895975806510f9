"""Every experiment or calibration key a message names ("section.key" inside a string literal of
the sources) is one the files accept: a message must never send a user to a key that the
experiment file then refuses as unknown. The keys are those of the references the program
writes (docs/experiment.md, docs/calibration.md), which tests/test_app.cpp keeps up to date."""
import os
import re

SOURCE = os.environ["BRECCIA_SOURCE_DIR"]
SECTIONS = ("engine", "material", "sample", "contact", "bond", "joint", "test", "output", "ae",
            "loading", "calibration", "targets")
# "section.key" inside a literal; a file name ("sample.geom", "test.toml") is not a key.
NAMED = re.compile(r"\b(" + "|".join(SECTIONS) + r")\.([a-z][a-z0-9_]*)\b")
FILE_ENDINGS = {"geom", "toml", "json", "csv", "txt", "bin", "png", "html", "md", "py", "cpp",
                "hpp", "log", "vtu", "vtp", "pvd", "xyzr", "geo", "tmp"}
LITERAL = re.compile(r'"((?:[^"\\\n]|\\.)*)"')
# The old [loading] table is still read (docs/experiment.md says which of its keys).
LOADING = {"platen_speed", "ramp_time", "max_strain", "stop_fraction", "confining_stress",
           "servo_relaxation"}


def reference_keys():
    """section.key of every row of the two references, by the section heading above it."""
    keys = {"loading." + k for k in LOADING}
    for name, default in (("experiment.md", None), ("calibration.md", None)):
        section = default
        with open(os.path.join(SOURCE, "docs", name), encoding="utf-8") as f:
            for line in f:
                heading = re.match(r"#+ .*\[([a-z]+)", line)
                if heading:
                    section = heading.group(1)
                    continue
                row = re.match(r"\| (`[^|]+`)", line)
                if row and section:
                    for key in re.findall(r"`([a-z_0-9.]+)`", row.group(1)):
                        keys.add(key if "." in key else section + "." + key)
    return keys


def named_keys():
    """(file, line, section.key) of every key named in a literal of the sources."""
    found = []
    for top in ("src", "apps", "python/src"):
        for folder, _, files in os.walk(os.path.join(SOURCE, top)):
            for name in sorted(files):
                if not name.endswith((".cpp", ".hpp")):
                    continue
                path = os.path.join(folder, name)
                with open(path, encoding="utf-8") as f:
                    for number, line in enumerate(f, 1):
                        if line.lstrip().startswith("//"):
                            continue
                        for literal in LITERAL.findall(line):
                            for section, key in NAMED.findall(literal):
                                if key not in FILE_ENDINGS:
                                    found.append((os.path.relpath(path, SOURCE), number,
                                                  section + "." + key))
    return found


def test_the_references_list_the_keys():
    keys = reference_keys()
    for key in ("sample.bond_gap_tolerance", "test.confining_stress", "bond.installation_gap",
                "output.checkpoint_interval_s", "calibration.grip_speed",
                "targets.tensile_strength"):
        assert key in keys, key
    assert "sample.max_steps" not in keys


def test_every_key_a_message_names_exists():
    keys = reference_keys()
    named = named_keys()
    assert len(named) > 100, "the scan must find the keys the messages name"
    missing = [f"{path}:{line}: {key}" for path, line, key in named if key not in keys]
    assert not missing, "messages name keys that do not exist:\n" + "\n".join(missing)
