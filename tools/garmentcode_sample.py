"""Generate a varied, reproducible set of GarmentCode *_specification.json files.

Run from the root of a GarmentCode checkout (https://github.com/maria-korosteleva/GarmentCode,
MIT; used at d449629, 2025-06-29), so that `assets` and `pygarment` import, in a Python with
pyyaml, numpy<2, scipy, svgwrite, svgpathtools, matplotlib, CairoSVG and psutil (pattern
generation needs nothing of its simulator):
    cd GarmentCode && python /path/to/drapekit/tools/garmentcode_sample.py --out OUT --seed 20240517
Then `tools/garmentcode_sweep.sh OUT RESULTS [drapekit garment flags]` drapes each on the body
it was made for. The output is not in the repository (generated: 40 files, about 2 MB with their design parameters); the README
(`drapekit garment`, "Patterns from GarmentCode's generator") says what the sweep found.

Designs are sampled with pyg.DesignSampler on assets/design_params/default.yaml
(as pattern_sampler.py does) and filtered with the sampler's own rejection rules
(assert_param_combinations, assert_total_length, is_self_intersecting, empty).
To guarantee coverage of rarer features, the first slots use *conditional*
rejection sampling: keep drawing from the sampler until a draw has a wanted
feature (e.g. a hood); the remaining slots are unconditioned random draws.
"""
import argparse
import json
import random
import sys
import traceback
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path.cwd()))
import pygarment as pyg  # noqa: E402
from assets.bodies.body_params import BodyParameters  # noqa: E402
from assets.garment_programs.meta_garment import MetaGarment  # noqa: E402
from pattern_sampler import assert_param_combinations  # noqa: E402  (sampler's own filter)

BODIES = {
    'ma': 'assets/bodies/mean_all.yaml',
    'mf': 'assets/bodies/mean_female.yaml',
    'mm': 'assets/bodies/mean_male.yaml',
}

U_SHORT = {'FittedShirt': 'fshirt', 'Shirt': 'shirt', None: ''}
B_SHORT = {
    'SkirtCircle': 'circle', 'AsymmSkirtCircle': 'asymcircle', 'GodetSkirt': 'godet',
    'Pants': 'pants', 'Skirt2': 'skirt2', 'SkirtManyPanels': 'manypanel',
    'PencilSkirt': 'pencil', 'SkirtLevels': 'levels', None: ''}
W_SHORT = {'StraightWB': 'swb', 'FittedWB': 'fwb', None: ''}


def v(design, *path):
    d = design
    for p in path:
        d = d[p]
    return d['v']


def category(design):
    up, bot = v(design, 'meta', 'upper'), v(design, 'meta', 'bottom')
    if up and bot == 'Pants':
        return 'jumpsuit'
    if up and bot:
        return 'dress'
    if up:
        return 'top'
    if bot == 'Pants':
        return 'pants'
    if bot:
        return 'skirt'
    return 'belt'


def panel_features(panel_names):
    """Features actually present in the assembled pattern (from panel names)"""
    f = []
    if any('hood' in p for p in panel_names):
        f.append('hood')
    if any('collar' in p for p in panel_names):
        f.append('collar')
    if any('sleeve' in p for p in panel_names):
        f.append('slv')
    if any('cuff' in p for p in panel_names):
        f.append('cuff')
    return f


def strapless_sides(panels):
    """Sides whose bodice is actually strapless (GarmentCode only applies `strapless`
    to FittedShirt; it labels the cropped top edges 'strapless_top')."""
    sides = []
    for side in ('right', 'left'):
        if any(e.get('label') == 'strapless_top'
               for n, p in panels.items() if n.startswith(side) for e in p['edges']):
            sides.append(side)
    return sides


def tag(design, panel_names, panels=None):
    parts = [category(design), U_SHORT[v(design, 'meta', 'upper')],
             W_SHORT[v(design, 'meta', 'wb')], B_SHORT[v(design, 'meta', 'bottom')]]
    feats = panel_features(panel_names)
    if 'collar' in feats:
        style = v(design, 'collar', 'component', 'style')
        feats[feats.index('collar')] = {'Turtle': 'turtle', 'SimpleLapel': 'lapel'}.get(style, 'collar')
    parts += [f for f in feats if f != 'cuff']
    if v(design, 'meta', 'upper'):
        sl = strapless_sides(panels or {})
        if len(sl) == 2:
            parts.append('strapless')
        elif sl:
            parts.append(f'strapless{sl[0][0].upper()}')
        if v(design, 'left', 'enable_asym'):
            parts.append('asym')
    return '-'.join(p for p in parts if p)


def summary(design):
    up, wb, bot = v(design, 'meta', 'upper'), v(design, 'meta', 'wb'), v(design, 'meta', 'bottom')
    s = [f'cat={category(design)}', f'upper={up}', f'waistband={wb}', f'bottom={bot}']
    if up:
        strapless = v(design, 'shirt', 'strapless')
        s.append(f'strapless_param={strapless}' + ('' if up == 'FittedShirt' or not strapless else '(ignored:not fitted)'))
        s.append(f"shirt_len={v(design, 'shirt', 'length'):.2f}")
        if not strapless:
            s.append(f"collar(f/b)={v(design, 'collar', 'f_collar')}/{v(design, 'collar', 'b_collar')}")
            s.append(f"collar_comp={v(design, 'collar', 'component', 'style')}")
            if v(design, 'sleeve', 'sleeveless'):
                s.append('sleeves=none')
            else:
                s.append(f"sleeves=yes(armhole={v(design, 'sleeve', 'armhole_shape')},"
                         f"len={v(design, 'sleeve', 'length'):.2f},cuff={v(design, 'sleeve', 'cuff', 'type')})")
        if v(design, 'left', 'enable_asym'):
            s.append(f"asym_left(strapless={v(design, 'left', 'shirt', 'strapless')},"
                     f"sleeveless={v(design, 'left', 'sleeve', 'sleeveless')},"
                     f"collar={v(design, 'left', 'collar', 'f_collar')})")
    if bot == 'Pants':
        s.append(f"pants(len={v(design, 'pants', 'length'):.2f},flare={v(design, 'pants', 'flare'):.2f},"
                 f"cuff={v(design, 'pants', 'cuff', 'type')})")
    elif bot in ('SkirtCircle', 'AsymmSkirtCircle', 'SkirtManyPanels'):
        s.append(f"flare_skirt(len={v(design, 'flare-skirt', 'length'):.2f},suns={v(design, 'flare-skirt', 'suns'):.2f},"
                 f"cut={v(design, 'flare-skirt', 'cut', 'add')})")
        if bot == 'SkirtManyPanels':
            s.append(f"n_panels={v(design, 'flare-skirt', 'skirt-many-panels', 'n_panels')}")
    elif bot == 'GodetSkirt':
        s.append(f"godet(base={v(design, 'godet-skirt', 'base')},inserts={v(design, 'godet-skirt', 'num_inserts')})")
    elif bot == 'SkirtLevels':
        s.append(f"levels(base={v(design, 'levels-skirt', 'base')},level={v(design, 'levels-skirt', 'level')},"
                 f"n={v(design, 'levels-skirt', 'num_levels')})")
    elif bot == 'PencilSkirt':
        s.append(f"pencil(len={v(design, 'pencil-skirt', 'length'):.2f},side_cut={v(design, 'pencil-skirt', 'style_side_cut')})")
    elif bot == 'Skirt2':
        s.append(f"skirt2(len={v(design, 'skirt', 'length'):.2f},ruffle={v(design, 'skirt', 'ruffle'):.2f})")
    return '; '.join(s)


# Feature targets for the conditioned slots: (name, predicate)
def _up(d): return v(d, 'meta', 'upper')
def _bot(d): return v(d, 'meta', 'bottom')
def _has_sleeves(d): return _up(d) and not v(d, 'shirt', 'strapless') and not v(d, 'sleeve', 'sleeveless')


TARGETS = [
    ('hood', lambda d: _up(d) and not v(d, 'shirt', 'strapless') and v(d, 'collar', 'component', 'style') == 'Hood2Panels'),
    ('turtle', lambda d: _up(d) and not v(d, 'shirt', 'strapless') and v(d, 'collar', 'component', 'style') == 'Turtle'),
    ('lapel', lambda d: _up(d) and not v(d, 'shirt', 'strapless') and v(d, 'collar', 'component', 'style') == 'SimpleLapel'),
    ('jumpsuit', lambda d: _up(d) and _bot(d) == 'Pants'),
    ('pants', lambda d: not _up(d) and _bot(d) == 'Pants'),
    ('godet', lambda d: _bot(d) == 'GodetSkirt'),
    ('levels', lambda d: _bot(d) == 'SkirtLevels'),
    ('circle', lambda d: _bot(d) == 'SkirtCircle'),
    ('asymcircle', lambda d: _bot(d) == 'AsymmSkirtCircle'),
    ('manypanels', lambda d: _bot(d) == 'SkirtManyPanels'),
    ('pencil', lambda d: _bot(d) == 'PencilSkirt'),
    ('skirt2', lambda d: _bot(d) == 'Skirt2'),
    ('strapless', lambda d: _up(d) and v(d, 'shirt', 'strapless')),
    ('asym_left', lambda d: _up(d) and v(d, 'left', 'enable_asym')),
    ('sleeve_cuff', lambda d: _has_sleeves(d) and v(d, 'sleeve', 'cuff', 'type')),
    ('top_only_sleeves', lambda d: _has_sleeves(d) and not _bot(d)),
    ('fitted_wb', lambda d: v(d, 'meta', 'wb') == 'FittedWB'),
    ('straight_wb_skirt', lambda d: v(d, 'meta', 'wb') == 'StraightWB' and _bot(d) and not _up(d)),
]


def try_build(design, body, name):
    """Sampler's validity checks. Returns (piece, pattern) or raises/returns None."""
    assert_param_combinations(design)
    piece = MetaGarment(name, body, design)
    piece.assert_total_length()
    if piece.is_self_intersecting():
        return None
    pattern = piece.assembly()
    if len(pattern.pattern['panels']) == 0:
        return None
    return piece, pattern


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--out', required=True)
    ap.add_argument('--seed', type=int, default=20240517)
    ap.add_argument('--n_ma', type=int, default=24)
    ap.add_argument('--n_mf', type=int, default=8)
    ap.add_argument('--n_mm', type=int, default=8)
    ap.add_argument('--design_file', default='assets/design_params/default.yaml')
    args = ap.parse_args()

    random.seed(args.seed)
    np.random.seed(args.seed)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    bodies = {k: BodyParameters(p) for k, p in BODIES.items()}
    sampler = pyg.DesignSampler(args.design_file)

    slots = ['ma'] * args.n_ma + ['mf'] * args.n_mf + ['mm'] * args.n_mm
    # spread targets over slots: assign targets round-robin, bodies interleaved
    order = []
    per_body = {b: [i for i, s in enumerate(slots) if s == b] for b in BODIES}
    # interleave so that each body gets some conditioned targets
    inter = []
    while any(per_body.values()):
        for b in ('ma', 'mf', 'ma', 'mm'):
            if per_body[b]:
                inter.append(per_body[b].pop(0))
    order = inter
    targets = {slot_i: TARGETS[k] for k, slot_i in enumerate(order[:len(TARGETS)])}

    index_lines = []
    rejects = Counter()
    for n, slot_i in enumerate(sorted(range(len(slots)))):
        body_key = slots[slot_i]
        body = bodies[body_key]
        target = targets.get(slot_i)
        for attempt in range(5000):
            design = sampler.randomize()
            if target and not target[1](design):
                continue
            name = f'gc_{body_key}_{n:02d}'
            try:
                res = try_build(design, body, name)
            except BaseException as e:  # sampler treats any failure as rejection
                if isinstance(e, KeyboardInterrupt):
                    raise
                rejects[type(e).__name__] += 1
                continue
            if res is None:
                rejects['self_intersecting_or_empty'] += 1
                continue
            piece, pattern = res
            break
        else:
            print(f'slot {n}: no valid design found for target {target and target[0]}')
            continue

        t = tag(design, list(pattern.pattern['panels']), pattern.pattern['panels'])
        # deterministic key order (Component assembly iterates a python set)
        pattern.pattern['panels'] = dict(sorted(pattern.pattern['panels'].items()))
        pattern.pattern['stitches'] = sorted(pattern.pattern['stitches'], key=lambda st: json.dumps(st, sort_keys=True))
        fname = f'{t}_{body_key}_{n:02d}_specification.json'
        pattern.name = fname[:-len('_specification.json')]
        with open(out / fname, 'w') as f:
            json.dump(pattern.spec, f, indent=2)
        # keep design params alongside for reproducibility/debugging
        import yaml
        dpdir = out / 'design_params'
        dpdir.mkdir(exist_ok=True)
        with open(dpdir / fname.replace('_specification.json', '_design_params.yaml'), 'w') as f:
            yaml.dump({'design': design}, f, default_flow_style=False, sort_keys=False)

        n_panels = len(pattern.pattern['panels'])
        line = (f'{fname}\tbody={Path(BODIES[body_key]).stem}\tpanels={n_panels}\t'
                f'stitches={len(pattern.pattern["stitches"])}\t'
                f'target={target[0] if target else "random"}\t{summary(design)}; '
                f'panel_features={"+".join(panel_features(list(pattern.pattern["panels"]))) or "none"}; '
                f'effective_strapless_sides={"+".join(strapless_sides(pattern.pattern["panels"])) or "none"}')
        index_lines.append(line)
        print(line, flush=True)

    with open(out / 'INDEX.txt', 'w') as f:
        f.write('# file\tbody\tpanels\tstitches\tselection\tdesign summary\n')
        f.write('\n'.join(index_lines) + '\n')
    print('Rejections:', dict(rejects))
    print(f'Wrote {len(index_lines)} specs to {out}')


if __name__ == '__main__':
    main()
