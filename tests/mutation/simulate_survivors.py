#!/usr/bin/env python3
"""The independent check of geometric survivors whose safety rests on mochi's proof alone:
applies each listed mutant of tests/mutation-survivors.toml (the `urdf-*` and `pose-*`
operators of tests/mutation/ops.rs, re-implemented here on the text) to a private copy of
choreographies/, motion-primitives/ and robots/, and runs `mochi simulate` (parry distances
of the real bodies, independent of the SMT proofs) on its example with several seeds. A
collision the simulator reports on a mutant that `mochi check` verifies is a false
`verified`: the output says so.

Usage: tests/mutation/simulate_survivors.py [ID ...]   (default: the groups below)
Environment: MOCHI (the binary, default target/release/mochi), SEEDS (default "1 2 3"),
RUNS (default 3), STEPS (default 80). Writes one line per mutant and seed, tab-separated:
id, seed, exit code, seconds, the simulator's summary line."""
import os, re, shutil, subprocess, sys, tempfile, time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MOCHI = os.environ.get('MOCHI', os.path.join(ROOT, 'target/release/mochi'))
SEEDS = os.environ.get('SEEDS', '1 2 3').split()
RUNS, STEPS = os.environ.get('RUNS', '3'), os.environ.get('STEPS', '80')
PANDA = 'sorting-case-study.chor@robots/example-robot-data/robots/panda_description/urdf/panda_collision.urdf'
DEFAULT = [
    # Moveo urdf-scale
    'mounted-arm.chor@robots/moveo_urdf/urdf/moveo_urdf.urdf:450:9:urdf-scale',
    'mounted-arm.chor@robots/moveo_urdf/urdf/moveo_urdf.urdf:626:9:urdf-scale',
    'sorting-case-study.chor@robots/moveo_urdf/urdf/moveo_urdf.urdf:509:9:urdf-scale',
    'sorting-case-study.chor@robots/moveo_urdf/urdf/moveo_urdf.urdf:626:9:urdf-scale',
    # the Moveo's place moved by 0.05 m
    'sorting-case-study.chor@robots/moveo.mochi:38:56:pose-y-',
    # the Panda's collision elements moved by 0.03 m
] + [PANDA + ':' + s for s in (
    '161:13:urdf-move+x', '161:13:urdf-move-z', '200:13:urdf-move+x', '200:13:urdf-move-z', '230:13:urdf-move-z',
    '263:13:urdf-move+y', '269:13:urdf-move-z', '26:13:urdf-move+y', '308:13:urdf-move+y', '320:13:urdf-move+x',
    '320:13:urdf-move-z', '326:13:urdf-move+x', '382:13:urdf-move-z', '56:13:urdf-move+y', '89:13:urdf-move-z')]

def offset(text, line, col):
    lines = text.split('\n')
    return sum(len(l) + 1 for l in lines[:line - 1]) + col - 1

def urdf(text, line, col, op):
    off = offset(text, line, col)
    tag = text[off:text.index('>', off)]
    if op == 'urdf-scale':
        assert tag.startswith('<mesh'), tag
        m = re.search(r'\sscale="([^"]*)"', tag)
        if m:
            nv = ' '.join(repr(float(x) * 1.2) for x in m.group(1).split())
            return text[:off + m.start(1)] + nv + text[off + m.end(1):]
        return text[:off + 5] + ' scale="1.2 1.2 1.2"' + text[off + 5:]
    m = re.match(r'urdf-move([+-])([xyz])$', op)
    assert m and tag.startswith('<origin'), (op, tag)
    x = re.search(r'xyz="([^"]*)"', tag)
    v = [float(s) for s in x.group(1).split()]
    v['xyz'.index(m.group(2))] += 0.03 if m.group(1) == '+' else -0.03
    return text[:off + x.start(1)] + ' '.join(repr(c) for c in v) + text[off + x.end(1):]

def pose(text, line, col, op):
    off = offset(text, line, col)
    assert text[off:off + 4] == 'pose'
    i = text.index('(', off) + 1
    depth, start, args, j = 0, i, [], i
    while True:
        c = text[j]
        if c == '(':
            depth += 1
        elif c == ')':
            if depth == 0:
                args.append((start, j))
                break
            depth -= 1
        elif c == ',' and depth == 0:
            args.append((start, j))
            start = j + 1
        j += 1
    m = re.match(r'pose-(x|y|z|yaw)([+-])$', op)
    k = {'x': 0, 'y': 1, 'z': 2, 'yaw': 5}[m.group(1)]
    by = '0.1' if m.group(1) == 'yaw' else '0.05'
    a, b = args[k]
    while text[a] == ' ':
        a += 1
    return text[:a] + '(' + text[a:b] + ') ' + m.group(2) + ' ' + by + text[b:]

def main():
    ids = sys.argv[1:] or DEFAULT
    tree = tempfile.mkdtemp(prefix='mochi-survivors-')
    for d in ('choreographies', 'motion-primitives', 'robots'):
        shutil.copytree(os.path.join(ROOT, d), os.path.join(tree, d))
    try:
        for id_ in ids:
            example, rest = id_.split('@', 1)
            path, line, col, op = rest.rsplit(':', 3)
            original = open(os.path.join(ROOT, path)).read()
            edit = urdf if op.startswith('urdf-') else pose
            open(os.path.join(tree, path), 'w').write(edit(original, int(line), int(col), op))
            for seed in SEEDS:
                t = time.time()
                r = subprocess.run([MOCHI, 'simulate', os.path.join(tree, 'choreographies', example), '--runs', RUNS,
                                    '--steps', STEPS, '--seed', seed], capture_output=True, text=True)
                out = [l for l in (r.stdout + r.stderr).split('\n') if l.strip()]
                summary = out[-1] if out else ''
                print(f'{id_}\t{seed}\t{r.returncode}\t{time.time() - t:.0f}s\t{summary}', flush=True)
                if 'collision' in summary and 'no collision' not in summary:
                    print(f'POSSIBLE FALSE VERIFIED: {id_} (seed {seed}):\n' + r.stdout + r.stderr, flush=True)
            open(os.path.join(tree, path), 'w').write(original)
    finally:
        shutil.rmtree(tree)

if __name__ == '__main__':
    main()
