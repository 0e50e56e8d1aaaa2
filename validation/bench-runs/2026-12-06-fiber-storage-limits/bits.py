import numpy as np, zstandard as zs
exec(open('size.py').read().split("def tot")[0].replace("d=sys.argv[1]","d='/tmp/dump/silk'"))
def codes(i,q=0.25):
    x=v[i]; m=x.max(axis=1,keepdims=True); e=np.floor(np.log2(m))+1; sc=2.0**e
    h=(x/sc).astype(np.float16).view(np.uint16).astype(np.int64)
    k=keepbits(q*rs[i][None,:]*np.ones((NC,1)))
    ex=(h>>10)&31; lz=np.floor(np.log2(np.maximum(h,1))).astype(np.int64)
    after=np.where(ex==0, lz, 10); drop=np.where(h==0,0,np.maximum(after-k,0))
    half=np.where(drop>0,1<<np.maximum(drop-1,0),0); r=h+np.where(drop>0,half-1+((h>>drop)&1),0); r=(r>>drop)<<drop
    return r.astype(np.int64)
def byteshuf(c): return c.astype(np.uint16).reshape(-1).view(np.uint8).reshape(-1,2).T.copy().tobytes()
def bitshuf(c):
    a=c.astype(np.uint16).reshape(-1)
    bits=((a[None,:]>>np.arange(16)[:,None])&1).astype(np.uint8)
    return np.packbits(bits,axis=1).tobytes()
def chd(c): return np.concatenate([c[1:2],c[0:1]-c[1:2],c[2:3]-c[1:2]])&0xffff
def zz(c):  # zigzag of signed delta to keep small magnitudes small
    s=np.where(c>=0x8000,c-0x10000,c); return np.where(s>=0,2*s,-2*s-1)&0xffff
Z=zs.ZstdCompressor(level=15)
res={}
for i in range(n):
    c=codes(i)
    for name,b in [('byte',byteshuf(c)),('bit',bitshuf(c)),('chd+byte',byteshuf(chd(c))),('chd+zz+byte',byteshuf(zz(chd(c)))),('chd+zz+bit',bitshuf(zz(chd(c))))]:
        res[name]=res.get(name,0)+len(Z.compress(b))
for k,s in res.items(): print(k,'%.1f MB'%(s/n*8100/1e6))
