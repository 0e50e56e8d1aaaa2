import mpmath, math
mpmath.mp.prec = 200
worst = {'new':0,'old':0}
for line in open('d.txt'):
    u, a, b, c, d = map(float, line.split())
    x = 2*mpmath.pi*mpmath.mpf(u)
    s, co = mpmath.sin(x), mpmath.cos(x)
    for name, (p, q) in (('new',(a,b)),('old',(c,d))):
        for got, ex in ((p, s), (q, co)):
            ulp = math.ulp(float(ex)) if float(ex) != 0 else 5e-324
            e = abs(mpmath.mpf(got) - ex) / ulp
            worst[name] = max(worst[name], float(e))
print(worst)
