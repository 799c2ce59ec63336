#!/usr/bin/env python3
"""Off / shift / owen at one chain count, many seeds (R(E) across seeds, CPU time, FOM); interleaved, --threads 1."""
import csv, math, os, subprocess, sys, resource
BIN="target/release/lumest"
def run(scene, pts, n, seed, q):
    r0=resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([BIN,"illuminance","--scene",scene,"--points",pts,"--chains",str(n),"--seed",str(seed),"--qmc",q,"--threads","1","--quiet","--out","/tmp/e2.csv"],check=True,stderr=subprocess.DEVNULL)
    r1=resource.getrusage(resource.RUSAGE_CHILDREN)
    return r1.ru_utime-r0.ru_utime+r1.ru_stime-r0.ru_stime, [float(r["E"]) for r in csv.DictReader(open("/tmp/e2.csv"))]
def rel(samples):
    k=len(samples); acc=[]
    for col in zip(*samples):
        m=sum(col)/k; v=sum((x-m)**2 for x in col)/(k-1); acc.append(v/m**2)
    return math.sqrt(sum(acc)/len(acc))
print("| case | N | seeds | qmc | R(E) | T cpu [s] | FOM [1/s] |\n|---|---|---|---|---|---|---|")
for name,scene,pts,n,S in [("sobolev","data/sobolev.toml","data/sobolev_points.csv",8192,40),("sobolev","data/sobolev.toml","data/sobolev_points.csv",100000,40),("office","data/office.toml","data/office_grid.csv",100000,8)]:
    d={q:([],[]) for q in ["off","shift","owen"]}
    for s in range(1,S+1):
        for q in d:
            t,e=run(scene,pts,n,s,q); d[q][0].append(t); d[q][1].append(e)
    for q in d:
        t=sum(d[q][0])/S; r=rel(d[q][1])
        print(f"| {name} | {n} | {S} | {q} | {r:.3e} | {t:.3f} | {1/(r*r*t):.3e} |",flush=True)
