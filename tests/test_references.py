"""Citations of the reference manual point at sections that exist.

Code, messages, examples and docs cite docs/physics.md and docs/analysis.md by section
("physics.md §4.1"). Every such citation must name a heading of that page, and nothing may point
outside the repository (the manual is the project's own)."""
import os
import re
import subprocess

SOURCE = os.environ["BRECCIA_SOURCE_DIR"]
MANUALS = {"physics": "docs/physics.md", "analysis": "docs/analysis.md"}
# "physics.md §4.1", "analysis.md §5.4-§6.3", "physics.md §4.2 step 8": the first section number.
CITATION = re.compile(r"\b(physics|analysis)\.md,?\s*(?:§|Section\s+)(\d+(?:\.\d+)?)")


def tracked_text_files():
    files = subprocess.run(["git", "-C", SOURCE, "ls-files"], capture_output=True, text=True,
                           check=True).stdout.split()
    for name in files:
        path = os.path.join(SOURCE, name)
        if not os.path.isfile(path):
            continue
        try:
            with open(path, encoding="utf-8") as f:
                yield name, f.read()
        except UnicodeDecodeError:
            continue


def sections(manual):
    """Section numbers of the headings of a manual: "## 4. Bonds" gives 4, "### 4.1 (a) ..." 4.1."""
    with open(os.path.join(SOURCE, manual), encoding="utf-8") as f:
        text = f.read()
    return set(re.findall(r"^#{2,3} (\d+(?:\.\d+)?)\.? ", text, flags=re.M))


def test_the_manuals_have_their_sections():
    physics = sections(MANUALS["physics"])
    analysis = sections(MANUALS["analysis"])
    assert {"0.3", "1.5", "2.4", "3.2", "4.0", "4.3", "5", "6.2", "7.2", "9"} <= physics
    assert {"1.3", "2.2", "3.2", "4.1", "5.4", "6.2", "8", "10.6", "11", "13"} <= analysis


def test_every_citation_names_an_existing_section():
    known = {kind: sections(path) for kind, path in MANUALS.items()}
    wrong = []
    for name, text in tracked_text_files():
        for m in CITATION.finditer(text):
            kind, number = m.group(1), m.group(2)
            if number not in known[kind]:
                line = text.count("\n", 0, m.start()) + 1
                wrong.append(f"{name}:{line}: {m.group(0)}")
    assert not wrong, "citations of missing sections:\n" + "\n".join(wrong)


def test_nothing_points_outside_the_repository():
    outside = []
    for name, text in tracked_text_files():
        if name == "tests/test_references.py":
            continue
        for m in re.finditer(r"\.\./shared\b|\bshared/(?:physics|analysis|design)\.md", text):
            line = text.count("\n", 0, m.start()) + 1
            outside.append(f"{name}:{line}: {m.group(0)}")
    assert not outside, "references outside the repository:\n" + "\n".join(outside)
