#!/usr/bin/env bash
# Runs `lsgd eval` once per setting and prints one Markdown table row each.
#   scripts/sweep.sh DATASET_DIR MIN_GAP "label|yaml|mode" ...
# DATASET_DIR holds sequence.txt and groundtruth.txt; yaml is inline YAML
# flow text (e.g. "{segmentation: {superpixel_size: 30}}", or "{}" for the
# defaults) or @FILE for a config file; mode is exhaustive or nodes.
# Needs build/tools/lsgd/lsgd (or $LSGD).
set -euo pipefail
dir=$1; gap=$2; shift 2
lsgd=${LSGD:-build/tools/lsgd/lsgd}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
echo "| setting | mode | R@100P | AP | R@1 | R@5 | R@10 | ms/frame median | nodes |"
echo "|---|---|---|---|---|---|---|---|---|"
for spec in "$@"; do
  IFS='|' read -r label yaml mode <<<"$spec"
  if [[ $yaml == @* ]]; then cp "${yaml#@}" "$tmp/config.yaml"; else printf '%s\n' "$yaml" > "$tmp/config.yaml"; fi
  "$lsgd" eval --sequence "$dir/sequence.txt" --gt "$dir/groundtruth.txt" --min-gap "$gap" \
    --mode "$mode" --config "$tmp/config.yaml" --json "$tmp/out.json" > /dev/null
  /usr/bin/python3 - "$tmp/out.json" "$label" "$mode" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
print("| %s | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f | %d |" % (sys.argv[2], sys.argv[3],
      m["recall_at_100_precision"], m["average_precision"], m["recall_at_1"], m["recall_at_5"],
      m["recall_at_10"], m["ms_per_frame_median"], m["nodes"]))
PY
done
