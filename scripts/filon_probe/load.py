"""Reader of the data `build/bench/magnus_probe --export NOA DIR` writes (README.md)."""
import os
import numpy as np
def load(noa, d=None):
    d = d or os.path.join(os.environ.get("FILON_DATA", "build/filon_data"), f"d{noa}")
    meta = open(f"{d}/meta.txt").read().split()
    N, n = int(meta[0]), int(meta[1]); om = np.array([float(x) for x in meta[2:]])
    S = np.fromfile(f"{d}/S.bin").reshape(n+1, n+1); Si = np.fromfile(f"{d}/Sinv.bin").reshape(n+1, n+1)
    P = [np.fromfile(f"{d}/samples_p{p}.bin").reshape(-1, 5+(n+1)**2) for p in (0,1)]
    refs = {k: np.fromfile(f"{d}/ref_{k}.bin").reshape(-1, 1+4*N) for k in (13,14)}
    return dict(N=N, n=n, om=om, S=S, Si=Si, P=P, refs=refs)
