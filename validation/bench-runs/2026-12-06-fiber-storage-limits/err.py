import numpy as np, sys
exec(open('size.py').read().split("def tot")[0].replace("d=sys.argv[1]","d='/tmp/dump/silk'"))
def dec(i,q,absub):
    x=v[i]; m=x.max(axis=1,keepdims=True); e=np.floor(np.log2(m))+1; sc=2.0**e
    h=(x/sc).astype(np.float16).view(np.uint16).astype(np.int64)
    tol=q*rs[i][None,:]*np.ones((NC,1)); k=keepbits(tol)
    ex=(h>>10)&31; lz=np.floor(np.log2(np.maximum(h,1))).astype(np.int64)
    after=np.where((ex==0)&(not absub), lz, 10); drop=np.where(h==0,0,np.maximum(after-k,0))
    half=np.where(drop>0,1<<np.maximum(drop-1,0),0); r=h+np.where(drop>0,half-1+((h>>drop)&1),0); r=(r>>drop)<<drop
    return r.astype(np.uint16).view(np.float16).astype(np.float64)*sc
th=np.radians(np.arange(-90,91,2.0)); dO=((np.sin(th[1:])-np.sin(th[:-1]))[:,None]*np.radians(2.0)*np.ones((1,180))).reshape(-1)
for absub in (False,True):
    dm=[];rel_all=[];rel_met=[];own=[]
    for i in range(n):
        x=v[i]; y=dec(i,0.25,absub); m=x.max(axis=1,keepdims=True)
        dm.append(((y-x)*dO).sum(axis=1))
        nz=x>0; r=(y-x)/np.where(nz,x,1)
        rel_all.append(np.sqrt((r[nz]**2).mean())); met=x>=0.01*m; rel_met.append(np.sqrt((r[met]**2).mean()))
        s=rs[i][None,:].repeat(3,0); own.append(np.sqrt((s[nz]**2).mean()))
    dm=np.array(dm)
    print('absub',absub,'mass change max |%.2e| mean %.2e; RMS rel err all nonzero bins %.3f (own RMS rel SE %.3f), bins>=1%%max %.4f'%(abs(dm).max(),dm.mean(),np.mean(rel_all),np.mean(own),np.mean(rel_met)))
