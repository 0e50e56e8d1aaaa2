import numpy as np, zstandard as zs, sys
d=sys.argv[1] if len(sys.argv)>1 else '/tmp/dump/silk'; NB=90*180; NC=3
v=np.fromfile(d+'/vals.f64').reshape(-1,NC,NB)
rs=np.fromfile(d+'/relse.f64').reshape(-1,NB)
n=v.shape[0]
def keepbits(tol):
    with np.errstate(divide='ignore'):
        k=np.where(tol>0, np.ceil(-1-np.log2(np.where(tol>0,tol,1))), 10)
    return np.clip(k,0,10).astype(np.int64)
def rnd(h,k):
    h=h.astype(np.int64)
    ex=(h>>10)&31
    lz=np.floor(np.log2(np.maximum(h,1))).astype(np.int64)  # index of leading one
    after=np.where(ex==0, lz, 10)
    drop=np.maximum(after-k,0)
    drop=np.where(h==0,0,drop)
    half=np.where(drop>0, 1<<np.maximum(drop-1,0), 0)
    r=h+np.where(drop>0, half-1+((h>>drop)&1),0)
    return ((r>>drop)<<drop).astype(np.uint16)
def enc(i,q,floor=0.0,mode="plain",level=15,subflush=None):
    x=v[i]; out=[]
    m=x.max(axis=1,keepdims=True)
    e=np.floor(np.log2(np.where(m>0,m,1)))+1; sc=2.0**e
    y=(x/sc).astype(np.float16)
    h=y.view(np.uint16)
    tol=q*rs[i][None,:]*np.ones((NC,1))
    if floor>0:
        # absolute floor: tolerance at least floor (fraction of the part max) / value
        with np.errstate(divide='ignore',invalid='ignore'):
            tf=np.where(x>0, floor*m/x, 0)
        tol=np.maximum(tol,tf)
    k=keepbits(tol)
    h=rnd(h,k)
    if floor>0:
        # values below floor*m/2 → 0
        h=np.where((x< floor*m*0.5), 0, h).astype(np.uint16)
    if subflush is not None:
        h=np.where((h>>10)==0, 0, h).astype(np.uint16)
    hh=h.astype(np.int32)
    if mode=='chdelta':
        hh=np.concatenate([hh[1:2], hh[0:1]-hh[1:2], hh[2:3]-hh[1:2]]) & 0xffff
    if mode=='phidelta':
        g=hh.reshape(NC,90,180); g=np.concatenate([g[:,:,:1], np.diff(g,axis=2)],axis=2)&0xffff; hh=g.reshape(NC,NB)
    if mode=='both':
        hh=np.concatenate([hh[1:2], hh[0:1]-hh[1:2], hh[2:3]-hh[1:2]]) & 0xffff
        g=hh.reshape(NC,90,180); g=np.concatenate([g[:,:,:1], np.diff(g,axis=2)],axis=2)&0xffff; hh=g.reshape(NC,NB)
    b=hh.astype(np.uint16).reshape(-1).view(np.uint8).reshape(-1,2).T.copy().reshape(-1)
    return len(zs.ZstdCompressor(level=level).compress(b.tobytes()))
def tot(**kw):
    return sum(enc(i,**kw) for i in range(n))/n*8100/1e6
print('n',n)
for kw in [dict(q=0.25,subflush=0)]+[dict(q=0.25),dict(q=0.5),dict(q=0.25,mode='chdelta'),dict(q=0.25,mode='phidelta'),dict(q=0.25,floor=1e-4),dict(q=0.25,floor=1e-3),dict(q=0.25,floor=1e-4,mode='chdelta'),dict(q=0.25,level=19)]:
    print(kw, '%.1f MB'%tot(**kw))
