import numpy as np, sys
d=sys.argv[1] if len(sys.argv)>1 else '/tmp/dump/silk'; NB=90*180; NC=3
v=np.fromfile(d+'/vals.f64').reshape(-1,NC,NB)
rs=np.fromfile(d+'/relse.f64').reshape(-1,NB)
th=np.radians(np.arange(-90,91,2.0)); dO=(np.sin(th[1:])-np.sin(th[:-1]))[:,None]*np.radians(2.0)*np.ones((1,180)); dO=dO.reshape(-1)
m=v.max(axis=2,keepdims=True); e=np.floor(np.log2(m))+1; sc=2.0**e
sub = v < sc*2.0**-14
mass=(v*dO).sum(axis=2)
print('total mass (should be 1):', mass.min(), mass.max())
ms=(v*sub*dO).sum(axis=2)
print('subnormal-bin mass fraction: median %.2e max %.2e'%(np.median(ms),ms.max()))
print('fraction of bins subnormal (nonzero): %.3f, zero: %.3f'%(((v>0)&sub).mean(), (v==0).mean()))
rsub=rs[:,None,:].repeat(3,1)[sub&(v>0)]
print('rel SE of subnormal bins (undyed density): median %.2f, 10%% %.2f, 90%% %.2f'%tuple(np.percentile(rsub[rsub>0],[50,10,90])))
print('max f̂·ΔΩ share of a bin p_max median %.2e'%np.median((v*dO).max(axis=2)))
