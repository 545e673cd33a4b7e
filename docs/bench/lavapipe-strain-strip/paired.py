"""Per cell, the ratio of each binary's time to BASE's in the same round (runs next to each
other share the VM's phase more often than runs minutes apart), and the median and range
of those ratios over the rounds. Usage: python3 paired.py runs.txt BASE"""
import collections, statistics as st, sys

d = collections.defaultdict(dict)
cells, bins = [], []
for line in open(sys.argv[1]):
    f = line.split()
    if len(f) < 5:
        continue
    r, c, b, t = f[1], f[2], f[3], float(f[4])
    d[(c, b)][r] = t
    if c not in cells:
        cells.append(c)
    if b not in bins:
        bins.append(b)
base = sys.argv[2]
others = [b for b in bins if b != base]
print("| cell | " + " | ".join(f"{b}/{base} median (min–max)" for b in others) + " |")
print("|---|" + "---:|" * len(others))
for c in cells:
    cols = []
    for b in others:
        rs = [d[(c, b)][r] / d[(c, base)][r] for r in d[(c, b)] if r in d[(c, base)]]
        cols.append(f"{st.median(rs):.2f} ({min(rs):.2f}–{max(rs):.2f})" if rs else "-")
    print(f"| {c} | " + " | ".join(cols) + " |")
