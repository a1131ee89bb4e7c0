#!/usr/bin/python3
"""Where fitted surfaces stray from the truth (issue 13): every vertex of surfaces.ply (17 x 17
samples per patch, as surface.fit_bspline writes them) against 2 000 000 points sampled on the true
mesh; the error split by the sample's ring in its patch grid (0 = the patch's border), the worst
patches with their grid and distance to their quads, and the truth's sharp edges (dihedral
angles) within 4 mm of each worst place.

  bench/surface_error_places.py OUT_DIR TRUTH_MESH.off SCALE

OUT_DIR holds surfaces.ply and segments_report.json (a mesh-to-surfaces or cloud-to-surfaces run).
"""
import json, os, sys
from collections import defaultdict
import numpy as np
from scipy.spatial import cKDTree
def read_ply(p):
    data=open(p,'rb').read(); h=data.index(b'end_header\n')+11
    hdr=data[:h].decode().split('\n'); nv=int([l for l in hdr if l.startswith('element vertex')][0].split()[2])
    V=np.frombuffer(data[h:h+nv*24],dtype='<f8').reshape(-1,3); return V
def read_off(p,s):
    w=open(p).read().split(); nv,nf=int(w[1]),int(w[2]); V=np.array(w[4:4+3*nv],float).reshape(-1,3)*s
    F=[];at=4+3*nv
    for _ in range(nf):
        k=int(w[at]); F.append([int(x) for x in w[at+1:at+1+k]]); at+=1+k
    return V,np.array(F)
V=read_ply(os.path.join(sys.argv[1], "surfaces.ply")); TV,TF=read_off(sys.argv[2],float(sys.argv[3]))
# dense samples of the truth
rng=np.random.default_rng(0); A=TV[TF[:,0]];B=TV[TF[:,1]];C=TV[TF[:,2]]
area=np.linalg.norm(np.cross(B-A,C-A),axis=1)/2; n=2000000
fi=rng.choice(len(TF),n,p=area/area.sum()); r1=np.sqrt(rng.random(n));r2=rng.random(n)
P=(1-r1)[:,None]*A[fi]+(r1*(1-r2))[:,None]*B[fi]+(r1*r2)[:,None]*C[fi]
d,_=cKDTree(P).query(V)
g=17; per=g*g; npatch=len(V)//per
idx=np.arange(len(V))%per; i=idx//g; j=idx%g
bd=np.minimum(np.minimum(i,g-1-i),np.minimum(j,g-1-j))
for k in range(0,5):
    m=bd==k if k<4 else bd>=4
    print(f"grid ring {k}{'+' if k==4 else ''}: n={m.sum()} mean={d[m].mean():.3f} p99={np.percentile(d[m],99):.3f} max={d[m].max():.3f}")
r=json.load(open(os.path.join(sys.argv[1], "segments_report.json")))
rows=[]
for k,p in enumerate(r['patches']):
    dk=d[k*per:(k+1)*per]
    rows.append((dk.max(),k,p['grid'],p['mesh_distance_max'],p['min_normal_dot'],dk.mean()))
rows.sort(reverse=True)
for x in rows[:15]: print("patch %d grid %s maxerr %.3f mean %.3f  surface-to-quads %.3f  minnd %.2f"%(x[1],x[2],x[0],x[5],x[3],x[4]))
# dihedral angles of truth edges near worst points
from collections import defaultdict
N=np.cross(TV[TF[:,1]]-TV[TF[:,0]],TV[TF[:,2]]-TV[TF[:,0]]);N/=np.linalg.norm(N,axis=1)[:,None]
E=defaultdict(list)
for f,t in enumerate(TF):
    for a,b in ((t[0],t[1]),(t[1],t[2]),(t[2],t[0])): E[(min(a,b),max(a,b))].append(f)
ek=[];ang=[]
for e,fs in E.items():
    if len(fs)==2: ek.append(e); ang.append(np.degrees(np.arccos(np.clip(N[fs[0]]@N[fs[1]],-1,1))))
ek=np.array(ek);ang=np.array(ang);mid=(TV[ek[:,0]]+TV[ek[:,1]])/2
tree=cKDTree(mid)
for x in rows[:6]:
    k=x[1];dk=d[k*per:(k+1)*per];v=V[k*per+dk.argmax()]
    nb=tree.query_ball_point(v,4.0)
    a=ang[nb]; print(k, v.round(1), "edges within 4mm: max dihedral %.0f, n>30: %d"%(a.max() if len(a) else -1,(a>30).sum()), "angles>20:",sorted(set(np.round(a[a>20]).astype(int)))[:12])
