#!/usr/bin/env python3
"""Runs the worked example of docs/PYTHON.md as written: its ```python blocks, in order,
as one script, in a fresh folder where `assets` is the repository's, then checks the
files the example says it writes.

doc_example.py PYTHON.md SOURCE_DIR WORK_DIR
"""

import os
import re
import shutil
import subprocess
import sys


def example_code(markdown):
    blocks = re.findall(r"^```python\n(.*?)^```", markdown, flags=re.S | re.M)
    if not blocks:
        sys.exit("no ```python block in the document")
    return "\n".join(blocks)


def main(doc, source, work):
    with open(doc) as f:
        markdown = f.read()
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    os.symlink(os.path.join(source, "assets"), os.path.join(work, "assets"))
    script = os.path.join(work, "example.py")
    with open(script, "w") as f:
        f.write(example_code(markdown))
    subprocess.run([sys.executable, script], cwd=work, check=True)
    # The files the example writes, named in the document.
    written = re.findall(r"^- `([^`]+)`:", markdown, flags=re.M)
    if not written:
        sys.exit("the document lists no written file")
    missing = [name for name in written if not os.path.getsize(os.path.join(work, name))]
    if missing:
        sys.exit(f"the example did not write: {', '.join(missing)}")
    print(f"example ran; wrote {', '.join(written)}")


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit("usage: doc_example.py PYTHON.md SOURCE_DIR WORK_DIR")
    main(*sys.argv[1:])
