#!/usr/bin/python3
"""Checks that README.md shows examples/slam_loop.cc exactly as it is, and
that every line of code of its snippets of examples/localize.cc and
examples/relative_pose.cc is in that file (comments aside)."""
import pathlib
import sys

root = pathlib.Path(sys.argv[1])
example = (root / "examples" / "slam_loop.cc").read_text()
readme = (root / "README.md").read_text()
if "```cpp\n" + example + "```\n" not in readme:
    sys.exit("README.md does not show examples/slam_loop.cc as it is: copy the file into its cpp block")

for name, intro in (("localize.cc", "`examples/localize.cc` does both:"),
                    ("localize.cc", "ends by forgetting the map's\noldest frames:"),
                    ("relative_pose.cc", "`examples/relative_pose.cc` does it")):
    start = readme.index(intro)
    begin = readme.index("```cpp\n", start) + 7
    snippet = readme[begin:readme.index("```", begin)]
    lines = [line.split("//")[0].strip() for line in (root / "examples" / name).read_text().splitlines()]
    for line in snippet.splitlines():
        code = line.split("//")[0].strip()
        if code and code not in lines:
            sys.exit(f"README.md's snippet of examples/{name} has a line the file does not: {code}")
