#!/usr/bin/python3
# Where a frame's time goes when a robot describes it and a map stores it
# (docs/design.md, "Frames described apart from the map"): per frame,
# Detector.describe_frame() on one detector, process() of the description on
# another, and process() of the image on a third; medians and 95th
# percentiles in ms, shipped defaults, window 50.
#
#   PYTHONPATH=build/python /usr/bin/python3 scripts/describe_split.py SEQUENCE
import sys, statistics, time, lsgd
images = lsgd.open_sequence(sys.argv[1])
opts = {"search.min_gap": 50}
robot, mp, ref = lsgd.Detector(opts), lsgd.Detector(opts), lsgd.Detector(opts)
imgs = [lsgd.read_image(p) for p in images]
desc_ms, map_ms, img_ms = [], [], []
for img in imgs:
    t = time.perf_counter(); d = robot.describe_frame(img); desc_ms.append((time.perf_counter() - t) * 1e3)
    t = time.perf_counter(); mp.process(d); map_ms.append((time.perf_counter() - t) * 1e3)
    t = time.perf_counter(); ref.process(img); img_ms.append((time.perf_counter() - t) * 1e3)
q = lambda v: (statistics.median(v), sorted(v)[int(0.95 * len(v))])
print(sys.argv[1].split('/')[-2], "describe_frame %.2f / %.2f" % q(desc_ms), "process(description) %.2f / %.2f" % q(map_ms), "process(image) %.2f / %.2f" % q(img_ms))
