"""Classify a bake's rate-search probes by whether cheap bounds [L, U] decide every threshold the search compares
the probe's error with (speed43e study; input: stderr of a CB_STUDY-instrumented bake).

A throwaway, kept so the numbers in docs/speed.md can be made again: apply speed43e_bounds.patch to a checkout of
fecafd8 (it prints, per probe, L = the 8 scout rows' exact worst, U0 = the largest row bound, U = the row bounds with
each batch's top row skinned, E = the exact blends' worst, R = the baked rows' exact worst; and the search's probes,
candidate rates and answers), then
    CB_STUDY=1 build/crowdbake bake MODEL -q -o x.pal -j 1 2> study.txt
    python3 bench/study/speed43e_straddle.py study.txt
The patch is not for merging (a file-scope variable, getenv)."""
import re, sys

def parse(path):
    clips, cur, study = [], None, None
    for line in open(path):
        kv = dict(re.findall(r'(\w+)=([^ \n]+)', line))
        if line.startswith('CLIP'):
            cur = {'goal': float(kv['goal']), 'rates': [float(x) for x in kv['rates'].split(',') if x], 'probes': []}
            clips.append(cur)
        elif line.startswith('STUDY'):
            study = {k: float(v) for k, v in kv.items()}
        elif line.startswith('PROBE') and cur is not None:
            p = {k: float(v) for k, v in kv.items()}
            p['study'] = study if study and float(kv['goal']) > 0 else None
            study = None
            cur['probes'].append(p)
        elif line.startswith('ANSWER') and cur is not None:
            cur['answer'] = (float(kv['fps']), int(kv['fit']))
    return clips

def thresholds(p, rates, G):
    f, sampled = p['fps'], p['fit'] == 0
    ts = [G] + ([2 * G] if sampled else [])
    for g in rates:
        if g == f or g > p['max']: continue
        ts.append(1.5 * G * (g / f) ** 2)
        if sampled: ts.append(3 * G * (g / f) ** 2)
    return ts

def classify(path, ukey):
    out = {'probes': 0, 'exact (goal 0)': 0, 'met: answer': 0, 'met: decided': 0, 'met: straddle': 0,
           'goal straddled': 0, 'miss: decided': 0, 'miss: straddle': 0}
    bad = 0
    for c in parse(path):
        G = c['goal']
        for p in c['probes']:
            out['probes'] += 1
            s = p['study']
            if s is None: out['exact (goal 0)'] += 1; continue
            E = max(s['E'], s['R']); L = s['L']; U = max(s[ukey], s['R'])
            if not (L <= E <= U * (1 + 1e-12)): bad += 1
            ts = thresholds(p, c['rates'], G)
            if L <= G < U: out['goal straddled'] += 1; continue
            if U <= G:
                if c.get('answer') == (p['fps'], p['fit']): out['met: answer'] += 1; continue
                out['met: straddle' if any(L <= t < U for t in ts) else 'met: decided'] += 1
            else:
                out['miss: straddle' if any(G < t < U for t in ts) else 'miss: decided'] += 1
    out['unsound'] = bad
    return out

for path in sys.argv[1:]:
    for ukey in ('U0', 'U'):
        print(path.split('/')[-1], ukey, classify(path, ukey))

def truth(path):
    met = ans = miss = 0; mets_not_answer = []
    for c in parse(path):
        G = c['goal']
        for p in c['probes']:
            s = p['study']
            E = max(s['E'], s['R']) if s else p['e']
            if E <= G:
                met += 1
                if c.get('answer') == (p['fps'], p['fit']): ans += 1
                else: mets_not_answer.append((p['fps'], p['fit'], E / G))
            else: miss += 1
    return met, ans, miss, mets_not_answer
for path in sys.argv[1:]:
    print(path.split('/')[-1], 'met, of them answers, miss, met non-answers:', truth(path))
