#!/usr/bin/env python3
"""A dataset whose truth lists only part of the fruit, made from one with complete truth.

Usage: scripts/drop_truth.py SRC DST KEEP_FRACTION SEED

Writes DST/truth/*.json with each fruit kept with probability KEEP_FRACTION (Python's
random.Random(SEED), in file and fruit order) and "complete": false; links SRC's color/, depth/
and camera.json; leaves out mask/ (an instance mask would label every fruit). This is how a real
frame annotated only in part looks to training (docs/results.md, "Untagged fruit in training").
"""
import json, os, random, sys
src, dst, keep, seed = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
rng = random.Random(seed)
os.makedirs(os.path.join(dst, 'truth'), exist_ok=True)
for name in ('color', 'depth', 'camera.json'):
    if os.path.exists(os.path.join(src, name)) and not os.path.exists(os.path.join(dst, name)):
        os.symlink(os.path.abspath(os.path.join(src, name)), os.path.join(dst, name))
kept = total = 0
for f in sorted(os.listdir(os.path.join(src, 'truth'))):
    t = json.load(open(os.path.join(src, 'truth', f)))
    fruits = [x for x in t['fruits'] if rng.random() < keep]
    kept += len(fruits); total += len(t['fruits'])
    t['fruits'] = fruits
    t['complete'] = False
    json.dump(t, open(os.path.join(dst, 'truth', f), 'w'))
print(dst, 'kept', kept, 'of', total)
