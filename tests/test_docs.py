"""The docs: every citation of docs/model.md resolves, and the docstrings' examples run."""

import doctest
import importlib
import pkgutil
import re
from pathlib import Path

import pytest

import twoball

REPO = Path(__file__).resolve().parent.parent
CITATION = re.compile(r'docs/model\.md,?\s*\(?"([^"]+)"')


def _sections() -> set[str]:
    text = (REPO / "docs" / "model.md").read_text()
    return {line.lstrip("#").strip() for line in text.splitlines() if line.startswith("## ")}


def _sources():
    for folder in ("twoball", "tests", "app", "benchmarks", "docs"):
        yield from (REPO / folder).rglob("*.py")
        yield from (REPO / folder).rglob("*.md")
    yield REPO / "README.md"


def test_every_cited_section_of_docs_model_md_exists():
    sections = _sections()
    cited = {}
    for path in _sources():
        text = re.sub(r"\s*\n\s*(#\s*)?", " ", path.read_text())  # citations wrap across lines
        for name in CITATION.findall(text):
            cited.setdefault(name, path.relative_to(REPO))
    assert cited, "no citation found: the pattern is wrong"
    missing = {name: str(path) for name, path in cited.items() if name not in sections}
    assert not missing, missing


def test_no_reference_to_a_folder_outside_the_repository():
    # the library, the app, the benchmarks and tools, the tests and docs: an issue's number
    # means nothing to a reader of the code (it belongs in commit messages)
    paths = [*(REPO / "twoball").rglob("*.py"), *(REPO / "tests").rglob("*.py")]
    for folder in ("app", "benchmarks", "tools"):
        paths += (REPO / folder).glob("*.py")
    paths += [*(REPO / "docs").glob("*.md"), REPO / "README.md"]
    for path in paths:
        if path == Path(__file__).resolve():
            continue
        text = path.read_text()
        assert "shared/" not in text, path
        assert not re.search(r"\bissues? [0-9]+\b", text), path


LIBRARY = sorted(
    info.name
    for info in pkgutil.walk_packages(twoball.__path__, "twoball.")
    if info.name != "twoball.__main__"
)


@pytest.mark.parametrize("name", LIBRARY)
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    failed, _ = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert failed == 0, name


def test_the_public_functions_show_an_example():
    from twoball import model
    from twoball.batch import sweep

    public = (
        *(twoball.simulate, twoball.check_parameters, twoball.Result.evaluate, twoball.load_cube),
        *(sweep.sweep, sweep.Grid, sweep.parse_axis, sweep.plan),
        *(model.restitution, model.decay_ratio, model.floor_contact_time, model.icm_height),
    )
    for function in public:  # numpydoc: Parameters and Examples
        assert ">>>" in function.__doc__, function.__qualname__
        assert "Parameters\n" in function.__doc__, function.__qualname__
