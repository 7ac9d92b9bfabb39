"""Reads the run folders of the measurement scripts (scripts/ablation.sh, scripts/reconstruction-bench.sh):
OUT/<row>/<sequence>/<run>/ with summary.json and the scores written beside it."""
import json
import os


def collect(out, names, required):
    """[(row, sequence, [runs])] in sorted order; a run is a tuple of the loaded JSON files `names` (None where
    absent) and is left out when one of `required` is absent; rows without runs are left out."""
    rows = []
    for row in sorted(os.listdir(out)):
        rdir = os.path.join(out, row)
        if not os.path.isdir(rdir):
            continue
        for seq in sorted(os.listdir(rdir)):
            sdir = os.path.join(rdir, seq)
            if not os.path.isdir(sdir):
                continue
            runs = []
            for r in sorted(os.listdir(sdir)):
                paths = [os.path.join(sdir, r, n) for n in names]
                if not all(os.path.isfile(p) for p, n in zip(paths, names) if n in required):
                    continue
                runs.append(tuple(json.load(open(p)) if os.path.isfile(p) else None for p in paths))
            if runs:
                rows.append((row, seq, runs))
    return rows
