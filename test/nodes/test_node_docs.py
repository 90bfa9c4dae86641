"""Every node page shows the parameter table generated from its parameters module
(scripts/node_docs.py)."""

from __future__ import annotations

import importlib
import importlib.util
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "node_docs.py"


def _load_script():
    spec = importlib.util.spec_from_file_location("rns_node_docs_script", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


node_docs = _load_script()


@pytest.mark.parametrize("name", node_docs.PARAMETER_MODULES)
def test_every_node_page_shows_its_current_parameter_table(name):
    module = importlib.import_module(name)
    path = node_docs.page(module)
    assert path.is_file(), f"every node has a page: {path} is missing"
    texts = node_docs.current_text(module)
    assert texts is not None, f"{path} lacks the lines {node_docs.BEGIN} / {node_docs.END}"
    assert texts[0] == texts[1], f"stale table in {path}: run scripts/node_docs.py --write"


def test_the_table_replaces_only_the_text_between_the_markers():
    text = f"# rns_x\n\nbefore\n{node_docs.BEGIN}\nold table\n{node_docs.END}\nafter\n"
    updated = node_docs.with_table(text, "| new |")
    assert updated == f"# rns_x\n\nbefore\n{node_docs.BEGIN}\n| new |\n{node_docs.END}\nafter\n"
    assert node_docs.with_table(updated, "| new |") == updated
    assert node_docs.with_table("no markers\n", "| new |") is None
    assert node_docs.with_table(f"{node_docs.END}\n{node_docs.BEGIN}\n", "| new |") is None


def test_check_names_a_stale_page_and_write_makes_it_current(tmp_path, capsys, monkeypatch):
    from rns_ros.nodes import ptp_parameters

    path = tmp_path / f"{ptp_parameters.NODE_NAME}.md"
    path.write_text(f"# rns_ptp\n{node_docs.BEGIN}\n{node_docs.END}\n")
    monkeypatch.setattr(node_docs, "PAGES", tmp_path)
    assert node_docs.main(["--check"]) == 1
    assert str(path) in capsys.readouterr().err
    assert node_docs.main(["--write"]) == 0
    assert node_docs.main(["--check"]) == 0
    assert "| `method` | string | `three_phase` |" in path.read_text()
