"""The documentation's command-line reference (docs/reference/cli.md) is generated from the
argparse parsers (:mod:`upm.commands.cli_reference`): the committed page must be what the
generator makes now, on any terminal and any machine."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import pytest

from upm.cli import COMMANDS, build_parser
from upm.commands import cli_reference

pytestmark = pytest.mark.unit

REPO = Path(__file__).resolve().parent.parent


def test_committed_page_is_current():
    page = REPO / cli_reference.PAGE
    assert page.is_file(), f"{cli_reference.PAGE} is missing"
    assert page.read_text(encoding="utf-8") == cli_reference.render(), (
        f"{cli_reference.PAGE} is stale: run "
        "'.venv/bin/python -m upm.commands.cli_reference --write' and commit it")


def test_page_does_not_depend_on_the_terminal_width(monkeypatch):
    monkeypatch.setenv("COLUMNS", "40")
    narrow = cli_reference.render()
    monkeypatch.setenv("COLUMNS", "300")
    assert cli_reference.render() == narrow


def test_page_has_every_command_and_option():
    page = cli_reference.render()
    subparsers = next(a for a in build_parser()._actions
                      if isinstance(a, argparse._SubParsersAction))
    assert list(subparsers.choices) == list(COMMANDS)
    for name, sub in subparsers.choices.items():
        section = page.split(f"\n## upm {name}\n", 1)
        assert len(section) == 2, f"no section for upm {name}"
        body = section[1].split("\n## ", 1)[0]
        assert f"usage: upm {name} " in body
        for action in sub._actions:
            for option in action.option_strings:
                assert option in body, f"upm {name}: {option} missing from its section"


def test_page_names_no_machine_path():
    page = cli_reference.render()
    for path in {str(REPO), str(REPO.parent), os.path.expanduser("~")}:
        if len(path) > 1:
            assert path not in page


def test_write_puts_the_page_in_place(tmp_path, monkeypatch):
    monkeypatch.setattr(cli_reference, "REPO", tmp_path)
    assert cli_reference.main(["--write"]) == 0
    assert (tmp_path / cli_reference.PAGE).read_text(encoding="utf-8") == \
        cli_reference.render()
