#!/usr/bin/env python3
"""Cut cells per block of a sphere of radius 128 cells centred in a 512^3 grid (issue 40 item 5).

A cell counts as cut when its centre lies within sqrt(3)/2 of the sphere (an approximation of
the cells the surface crosses). Prints the total, then for the process grids 1 x 1 x 64,
1 x 8 x 8 and 1 x 16 x 32 (x never cut in 3-D) the largest and mean count per block, on the
block alone (halo 0), grown by 1 cell (the loads' window) and by 11 (the window steps 2, 4
and 5 of docs/mpi.md's plan would compute). Needs numpy; about a minute.
"""
import numpy as np
N=512; R=128.0; c=N/2
# cells whose centre lies within sqrt(3)/2 of the sphere: the cut cells (approximation)
half=np.sqrt(3)/2
cuts=[]  # (x,y,z) arrays per plane
ax=np.arange(N)+0.5-c
X,Y=np.meshgrid(ax,ax,indexing='ij')
counts_z=[]
cut_mask_planes={}
for k in range(N):
    z=ax[k]
    d=np.sqrt(X*X+Y*Y+z*z)
    m=np.abs(d-R)<half
    if m.any(): cut_mask_planes[k]=m
total=sum(m.sum() for m in cut_mask_planes.values())
print("cut cells", total)
def per_block(dims, halo):
    ky,kz=dims
    by=N//ky; bz=N//kz
    counts=np.zeros((ky,kz),dtype=np.int64)
    for k,m in cut_mask_planes.items():
        # cumulative over y of cut cells per y (sum over x)
        row=m.sum(axis=0)  # per y
        cs=np.concatenate([[0],np.cumsum(row)])
        for jz in range(kz):
            z0=jz*bz-halo; z1=(jz+1)*bz+halo
            if not (z0<=k<z1): continue
            for jy in range(ky):
                y0=max(0,jy*by-halo); y1=min(N,(jy+1)*by+halo)
                counts[jy,jz]+=cs[y1]-cs[y0]
    return counts
for dims in [(1,64),(8,8),(16,32)]:
    for h in [0,1,11]:
        cts=per_block(dims,h)
        print(dims,"halo",h,"max",cts.max(),"mean",round(cts.mean(),1),"max/mean",round(cts.max()/max(cts.mean(),1e-9),2))
