#!/usr/bin/python3
"""Evaluates the detector on a sequence and plots its precision-recall curve.

    PYTHONPATH=build/python /usr/bin/python3 python/examples/evaluate.py \
        ../shared/datasets/corridor/sequence.txt ../shared/datasets/corridor/groundtruth.txt 50 pr.png
"""
import sys

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402

import lsgd  # noqa: E402

sequence, groundtruth, min_gap, figure = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
images = lsgd.open_sequence(sequence)
gt = lsgd.load_groundtruth(groundtruth, frames=len(images))
detector = lsgd.Detector(search={"min_gap": min_gap})  # the shipped defaults otherwise
results = lsgd.run(detector, images)
m = lsgd.evaluate(results, gt, min_gap)
print(f"declared {m.declared_loops} loops ({m.declared_true} true, {m.declared_false} false); "
      f"R@100P {m.recall_at_100_precision:.3f}  AP {m.average_precision:.3f}  R@1 {m.recall_at_1:.3f}")

plt.plot([p.recall for p in m.curve], [p.precision for p in m.curve], label="lsgd (strict protocol)")
plt.scatter([m.recall_at_decision], [m.precision_at_decision], color="k", zorder=3,
            label=f"operating point: {m.declared_loops} declared loops")
plt.xlabel("recall")
plt.ylabel("precision")
plt.xlim(0, 1)
plt.ylim(0, 1.02)
plt.legend(loc="lower left")
plt.savefig(figure, dpi=120)
print("wrote", figure)
