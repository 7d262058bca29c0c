"""docs/PYTHON.md's examples run as written: its ```python blocks, in order, in one namespace, from the
repository's root."""
import os
import re

from conftest import ROOT


def test_docs_python_examples_run(tmp_path):
    text = (ROOT / "docs" / "PYTHON.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 5
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        ns = {"__name__": "docs_example", "TMP": str(tmp_path)}
        for i, code in enumerate(blocks):
            try:
                exec(compile(code, f"docs/PYTHON.md block {i + 1}", "exec"), ns)
            except Exception as e:  # name the block that failed
                raise AssertionError(f"docs/PYTHON.md block {i + 1} failed: {e!r}\n{code}") from e
    finally:
        os.chdir(cwd)
