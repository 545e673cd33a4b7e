import sys, statistics as st, collections
d=collections.defaultdict(list); order=[]; bins=[]
for l in open(sys.argv[1]):
    f=l.split()
    if len(f)<5:
        if len(f)==4 and f[2] not in order: order.append(f[2])
        continue
    c,b,t=f[2],f[3],float(f[4])
    d[(c,b)].append(t)
    if c not in order: order.append(c)
    if b not in bins: bins.append(b)
base=sys.argv[2] if len(sys.argv)>2 else bins[0]
print("cell", *[f"{b}(med,min-max)" for b in bins], *[f"{b}/{base}" for b in bins if b!=base], sep=" | ")
for c in order:
    meds={b:st.median(d[(c,b)]) for b in bins if d[(c,b)]}
    cols=[f"{meds[b]:.0f} ({min(d[(c,b)]):.0f}-{max(d[(c,b)]):.0f})" if b in meds else "-" for b in bins]
    print(c, *cols, *[f"{meds[b]/meds[base]:.2f}" if b in meds and base in meds else "-" for b in bins if b!=base], sep=" | ")
