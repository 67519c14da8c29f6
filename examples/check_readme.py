#!/usr/bin/python3
"""Checks that README.md shows examples/slam_loop.cc exactly as it is."""
import pathlib
import sys

root = pathlib.Path(sys.argv[1])
example = (root / "examples" / "slam_loop.cc").read_text()
readme = (root / "README.md").read_text()
if "```cpp\n" + example + "```\n" not in readme:
    sys.exit("README.md does not show examples/slam_loop.cc as it is: copy the file into its cpp block")
