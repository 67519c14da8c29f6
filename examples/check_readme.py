#!/usr/bin/python3
"""Checks that README.md shows examples/slam_loop.cc exactly as it is, and
that every line of code of its snippet of examples/localize.cc is in that
file (comments aside)."""
import pathlib
import sys

root = pathlib.Path(sys.argv[1])
example = (root / "examples" / "slam_loop.cc").read_text()
readme = (root / "README.md").read_text()
if "```cpp\n" + example + "```\n" not in readme:
    sys.exit("README.md does not show examples/slam_loop.cc as it is: copy the file into its cpp block")

start = readme.index("`examples/localize.cc` does both:")
snippet = readme[readme.index("```cpp\n", start) + 7:readme.index("```", readme.index("```cpp\n", start) + 7)]
localize = [line.split("//")[0].strip() for line in (root / "examples" / "localize.cc").read_text().splitlines()]
for line in snippet.splitlines():
    code = line.split("//")[0].strip()
    if code and code not in localize:
        sys.exit(f"README.md's snippet of examples/localize.cc has a line the file does not: {code}")
