import sys, glob, os, numpy as np
A, B = sys.argv[1], sys.argv[2]
for f in sorted(glob.glob(f'{A}/*.npy')):
    if f.endswith('.rgb.npy') or f.endswith('.parts.npy'): continue
    g = f.replace(A, B)
    a, b = np.load(f), np.load(g)
    ra, rb = np.load(f.replace('.npy', '.rgb.npy')), np.load(g.replace('.npy', '.rgb.npy'))
    pa, pb = np.load(f.replace('.npy', '.parts.npy')), np.load(g.replace('.npy', '.parts.npy'))
    print(f"{os.path.basename(f):34s} sdf differ {(a != b).sum():5d} max {np.abs(a-b).max():.2e} | rgb differ {(ra != rb).any(-1).sum():4d} max {np.abs(ra.astype(int)-rb).max()} | parts differ {(pa != pb).sum()}")
