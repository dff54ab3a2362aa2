"""The code blocks of a Markdown page (the README, the manual's pages): python blocks and shell commands."""

from __future__ import annotations

import re
from pathlib import Path

BLOCK = re.compile(r"^```(\w*)\n(.*?)^```", re.M | re.S)
SKIPPED = ("make ", "export ", ". ")  # set-up lines: make, environment, activation


def blocks(page: Path, kind: str) -> list[str]:
    """The bodies of the page's fenced blocks of language ``kind``."""

    return [body for language, body in BLOCK.findall(page.read_text()) if language == kind]


def shell_commands(page: Path) -> list[str]:
    """The lines of the page's ``sh`` blocks and the ``$ ``-prefixed lines of its plain blocks (set-up lines left out)."""

    commands = []
    for language, body in BLOCK.findall(page.read_text()):
        for line in body.splitlines():
            if language == "sh":
                command = re.sub(r"\s+#.*$", "", line).strip()
            elif language == "" and line.startswith("$ "):
                command = line[2:].strip()
            else:
                continue
            if command and not command.startswith("#") and not command.startswith(SKIPPED):
                commands.append(command)
    return commands
