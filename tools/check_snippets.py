#!/usr/bin/env python3
"""Checks that every ```cpp block in README.md and docs/*.md appears verbatim in a C++ file under
examples/, and every ```python block in a Python file under examples/python/ (which the tests
run), so that the docs show only code that compiles and runs. Exits 1 naming each stray snippet."""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
sources = "\n".join(p.read_text() for p in sorted((root / "examples").rglob("*"))
                    if p.suffix in {".cpp", ".hpp"})
python_sources = "\n".join(p.read_text() for p in sorted((root / "examples" / "python").rglob("*.py")))
docs = [root / "README.md", *sorted((root / "docs").glob("*.md"))]
failures = 0
checked = 0
for doc in docs:
    for language, where, text in (("cpp", "examples/", sources), ("python", "examples/python/", python_sources)):
        for match in re.finditer(rf"```{language}\n(.*?)```", doc.read_text(), re.S):
            checked += 1
            if match.group(1).rstrip("\n") not in text:
                first = match.group(1).strip().splitlines()[0]
                print(f"{doc.relative_to(root)}: {language} snippet not found in {where}: {first}")
                failures += 1
print(f"{checked - failures} passed, {failures} failed")
sys.exit(1 if failures else 0)
