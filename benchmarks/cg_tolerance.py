"""Effect of the CG tolerance (relative residual) on V and on the time per texture, default fidelity.

    python benchmarks/cg_tolerance.py 1e-7     # prints V of five standard textures, mean/max seconds, rounds
"""
import sys

import numpy as np

import roughness.simulate.linsolve as ls
from roughness.dataset.textures import standard_texture
from roughness.simulate import SimConfig, Simulator

rtol=float(sys.argv[1])
orig=ls.ConstrainedSystem.__init__
def init(self,*a,**k):
    k['rtol']=rtol; orig(self,*a,**k)
ls.ConstrainedSystem.__init__=init
sim=Simulator(SimConfig())
sim.run(standard_texture(1.0, seed=0))
out=[]
for lam,seed in [(0.75,1),(1.0,2),(1.25,3),(1.5,4),(0.625,5)]:
    r=sim.run(standard_texture(lam, seed=seed)); out.append((r.roughness, r.seconds, r.iterations))
print(rtol, [f'{v:.6f}' for v,_,_ in out], 'mean s', round(np.mean([s for _,s,_ in out]),2), 'max', round(max(s for _,s,_ in out),2), [i for *_,i in out])
