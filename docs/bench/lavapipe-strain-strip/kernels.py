"""Tabulates kernels.sh's reports: per backend, size and kernel, the median over the rounds
of each binary's ms per substep and the fastest round (a slow phase of the VM only adds
time, so the fastest round is the work's own cost), and STRIP's ratios of each."""
import collections, os, re, statistics as st, sys

root = sys.argv[1]
d = collections.defaultdict(list)
for run in sorted(r for r in os.listdir(root) if os.path.isdir(os.path.join(root, r))):
    which = run.rsplit("_", 1)[0].removeprefix("kb_")
    size, cols = None, []
    for line in open(os.path.join(root, run, "report.md")):
        m = re.match(r"## Per-kernel time at (\d+)×", line)
        if m:
            size, cols = int(m.group(1)), []
            continue
        if size and line.startswith("| kernel |"):
            # A column per backend, named by its solver: the API is the name's first word.
            cols = [c.strip().split("-")[0] for c in line.strip().strip("|").split("|")[1:]]
            continue
        if size and cols and line.startswith("| ") and not line.startswith("|---"):
            f = [c.strip() for c in line.strip().strip("|").split("|")]
            if f[0] in ("forces+springs+wind", "integrate+collide", "strain_limit", "substep"):
                for c, v in zip(cols, f[1:]):
                    try:
                        d[(c, size, f[0], which)].append(float(v))
                    except ValueError:
                        pass
        if line.startswith("## ") and not line.startswith("## Per-kernel"):
            size = None
keys = sorted({k[:3] for k in d})
print("| backend | n | kernel | 7015e92 median (fastest) | inline | strip | strip / 7015e92 | strip / inline |")
print("|---|---:|---|---:|---:|---:|---:|---:|")
for b, n, k in keys:
    ws = [w for w in ("A7015", "INLINE", "STRIP") if d[(b, n, k, w)]]
    m = {w: st.median(d[(b, n, k, w)]) for w in ws}
    lo = {w: min(d[(b, n, k, w)]) for w in ws}
    r = lambda a, c: f"{m[a] / m[c]:.2f} ({lo[a] / lo[c]:.2f})" if a in m and c in m else "-"
    print(f"| {b} | {n} | {k} | " + " | ".join(f"{m[w]:.2f} ({lo[w]:.2f})" if w in m else "-" for w in ("A7015", "INLINE", "STRIP"))
          + f" | {r('STRIP', 'A7015')} | {r('STRIP', 'INLINE')} |")
