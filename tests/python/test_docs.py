"""The getting-started example of docs/python.md runs as written (its first ```python block)."""

import os
import re
import subprocess
import sys

from conftest import SOURCE_DIR


def test_getting_started_example_runs(tmp_path):
    text = open(os.path.join(SOURCE_DIR, "docs", "python.md")).read()
    section = text.split("## Getting started", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    out = done.stdout.splitlines()
    assert out[0] == "hits per row: [0 3 3 0]"
    assert out[1:4] == ["[0.5 1. ]", "[ True False]", "[-0.5  1. ]"]
    assert out[4] == "[[0 1]]"
