#!/usr/bin/env python3
"""Bidirectional path filtering's weights in a discrete world, against the exact answer.

A brute-force check of whether BPF's MMIS weights (core/src/estimators/filter/bidir.rs)
sum to one in expectation over the ways a path can be built: a world of a few surface
cells and one light cell, where every cell is one kernel (K = 1 between any two nodes
in a cell, 0 across cells: the limit of tight clusters, in which "a kernel holds about
one camera node" is literal, and in which the approximate balance heuristic of
multi-vertex filtering is exact in expectation). A segment is a pair of cells (i, j); a node is a segment end.
The script traces camera paths and light paths as `nodes.rs` does (sequential sampling,
roulette q = albedo, the depth caps, light samples, emission, optional twins), forms the
denominators and rows by the rules of `bidir.rs`, propagates as `graph.rs` does, and
compares the mean pixel over many passes with the exact value of the discrete path sum.
Results (2026-11-28, recorded in docs/bidirectional-filtering.md, "Small kernels"):

  --passes 3000 --segments 12 --pixels 10 --light-paths 40   (sparse camera nodes)
  --passes 3000 --segments 5 --pixels 10 --light-paths 40    (the depth cap active)
  --passes 3000 --segments 12                                (dense)

Techniques for a segment (i, j), in one measure (K = 1):
  camera continuation of each camera node in i:   q_i P[i][j]
  light sample of each camera node in i that tries: nl_i          (j the light)
  adjoint continuation of each light node in j:   q_j P*[j][i]
  emission, N_L samples:                          N_L pe[i]       (j the light)

Variants (--variant):
  mvf         beta = 0 (no light paths);
  before      the estimator before twins (a light junction reuses what lies in its cell);
  twins       the fix: each light node w whose continuation reached a node gets a
              camera-kind twin at w (continuation and light sample, then a camera walk),
              left out of D of w's own arrival;
  twins-pair  twins, and a twin's segments also treated as conditioning the twin's light
              node (that node's term removed from D_a in the pair correction, as for a
              reached light node). Wrong: the twin's light node is a condition of the
              twin's sample, not a consequence of it; measured +2-3 % here.

Usage: scripts/bpf-weight-model.py [--passes N] [--seed S] [--variant V ...]
Prints mean pixel / exact with its standard error for each variant.
"""
import argparse
import random

LIGHT = -1  # the light cell

# The world: CELLS surface cells and one light, drawn once from a fixed seed. P[i]:
# where a camera continuation from i goes (a distribution over cells and the light);
# PS[j]: where an adjoint continuation from j goes; albedo RHO; light-sample probability
# NL; emission PE; camera primary PC. With many cells a path seldom comes back to a
# cell it visited, as a path in a continuous scene seldom comes back into a kernel it
# left (the estimator's rules assume it does not: a light junction counts the emission
# without its own path's).
CELLS = 40


def _world(seed=7):
    r = random.Random(seed)

    def dist(keys, extra=None):
        w = {k: 0.2 + r.random() for k in keys}
        total = sum(w.values())
        out = {k: v / total for k, v in w.items()}
        if extra is not None:
            out = {k: v * (1.0 - extra[1]) for k, v in out.items()}
            out[extra[0]] = extra[1]
        return out

    cells = range(CELLS)
    p = [dist(cells, (LIGHT, 0.05 + 0.2 * r.random())) for _ in cells]
    ps = [dist(cells) for _ in cells]
    rho = [0.4 + 0.4 * r.random() for _ in cells]
    nl = [0.5 + 0.5 * r.random() for _ in cells]
    return p, ps, rho, nl, dist(cells), dist(cells)


P, PS, RHO, NL, PE, PC = _world()
LE = 1.0


def exact(segments):
    """Pixel mean over paths of at most `segments` segments (primary included)."""
    out = [0.0] * CELLS  # radiance leaving cell i, L^(d)
    for _ in range(segments - 1):
        out = [sum(RHO[i] * p * (LE if j == LIGHT else out[j]) for j, p in P[i].items()) for i in range(CELLS)]
    return sum(pc * out[i] for i, pc in PC.items())


def pick(rng, dist):
    u, acc = rng.random(), 0.0
    for k, p in dist.items():
        acc += p
        if u < acc:
            return k
    return None  # the remainder: nothing


class Node:
    __slots__ = ("kind", "cell", "pred", "twin", "q", "next", "next_cell", "nee_tried", "nee", "seg")

    def __init__(self, kind, cell, pred):
        self.kind, self.cell, self.pred = kind, cell, pred
        self.twin = False
        self.q, self.next, self.next_cell = 0.0, None, None
        self.nee_tried, self.nee = False, False


def camera_walk(rng, nodes, cell, segments, max_segments, parent, first_node=None):
    """Camera nodes from a node at `cell` reached at segment `segments`."""
    node = first_node if first_node is not None else Node("cam", cell, parent)
    while True:
        if first_node is None or node is not first_node:
            if parent is not None:
                nodes[parent].next = len(nodes)
        idx = len(nodes)
        nodes.append(node)
        if cell == LIGHT:
            return  # the light does not reflect
        more = segments < max_segments
        if more:
            node.nee_tried = True
            node.nee = rng.random() < NL[cell]
            node.q = RHO[cell]
            if rng.random() < node.q:
                j = pick(rng, P[cell])
                node.next_cell = j
                parent, cell, segments = idx, j, segments + 1
                node = Node("cam", j, idx)
                continue
        return


def light_walk(rng, nodes, max_segments, twins):
    first = len(nodes)
    i = pick(rng, PE)
    prev, depth = None, 1  # the emission's segment reaches i
    cell = i
    while True:
        idx = len(nodes)
        n = Node("light", cell, prev)
        nodes.append(n)
        if prev is not None:
            nodes[prev].next = idx
        more = depth + 2 <= max_segments
        n.q = RHO[cell] if more else 0.0
        if more and rng.random() < n.q:
            j = pick(rng, PS[cell])
            n.next_cell = j
            prev, cell, depth = idx, j, depth + 1
            continue
        break
    if twins:
        for w in range(first, len(nodes)):
            if nodes[w].next is None:
                continue
            t = Node("cam", nodes[w].cell, w)
            t.twin = True
            # The twin takes its light sample and continuation at segment 2.
            camera_walk(rng, nodes, t.cell, 2, max_segments, None, first_node=t)


class Pass:
    def __init__(self, rng, pixels, light_paths, max_segments, twins):
        self.nodes, self.first = [], []
        self.light_paths = light_paths
        for _ in range(pixels):
            self.first.append(len(self.nodes))
            camera_walk(rng, self.nodes, pick(rng, PC), 1, max_segments, None)
        for _ in range(light_paths):
            light_walk(rng, self.nodes, max_segments, twins)
        self.memo = {}
        self.by_cell = {}
        for k, n in enumerate(self.nodes):
            self.by_cell.setdefault(n.cell, []).append(k)

    def arrival_start(self, u):
        """Light node u's arriving segment: (start cell, end cell)."""
        n = self.nodes[u]
        return (n.cell, LIGHT if n.pred is None else self.nodes[n.pred].cell)

    def d(self, i, j, skip_twin_of=None):
        """D of segment (i, j): (all, emission part)."""
        key = (i, j, skip_twin_of)
        if key not in self.memo:
            self.memo[key] = self._d(i, j, skip_twin_of)
        return self.memo[key]

    def _d(self, i, j, skip_twin_of):
        total = 0.0
        for t in self.by_cell.get(i, []):
            n = self.nodes[t]
            if n.kind != "cam" or (n.twin and n.pred == skip_twin_of):
                continue
            total += n.q * P[i].get(j, 0.0)
            if j == LIGHT and n.nee_tried:
                total += NL[i]
        if j != LIGHT:
            for t in self.by_cell.get(j, []):
                n = self.nodes[t]
                if n.kind == "light":
                    total += n.q * PS[j].get(i, 0.0)
        emit = self.light_paths * PE.get(i, 0.0) if j == LIGHT else 0.0
        return total + emit, emit

    def light_term(self, u, a):
        """Light node u's term in D of segment a = (start, end)."""
        n = self.nodes[u]
        return n.q * PS[n.cell].get(a[0], 0.0) if n.cell == a[1] else 0.0

    def rows(self, twin_pair):
        """Each node's row: (emission, direct, [(target, coefficient)])."""
        rows = []
        for v, n in enumerate(self.nodes):
            if n.kind == "cam" and n.twin:
                rows.append((0.0, 0.0, []))
                continue
            if n.cell == LIGHT:
                rows.append((LE, 0.0, []))
                continue
            if n.kind == "cam":
                centre, a = v, None
                if n.pred is not None and self.nodes[n.pred].kind == "cam":
                    a = (self.nodes[n.pred].cell, n.cell)
                    d_a = self.d(*a)[0]
                light_junction = False
                emitted = 0.0
            else:
                if n.pred is None:
                    rows.append((LE, 0.0, []))  # first hit: the light's emission only
                    continue
                centre = n.pred
                a = self.arrival_start(v)
                d_a = self.d(*a, skip_twin_of=v)[0]
                light_junction = True
                emitted = 0.0
            c = self.nodes[centre].cell
            direct, pairs = 0.0, []
            for u in self.by_cell.get(c, []):
                m = self.nodes[u]
                if m.kind == "light" and light_junction and u == centre:
                    continue  # its own arrival
                if m.kind == "cam":
                    dep = 0.0
                    if a is not None and twin_pair and m.twin and m.pred != centre:
                        dep = self.light_term(m.pred, a)
                    segs = []
                    if m.next is not None:
                        segs.append((m.next_cell, m.next, None))
                    if m.nee:
                        segs.append((LIGHT, None, LE))
                else:
                    dep = self.light_term(u, a) if a is not None else 0.0
                    s = self.arrival_start(u)
                    segs = [(s[1], u, None)]
                for j, target, const in segs:
                    skip = u if m.kind == "light" else None
                    d_b, emit = self.d(c, j, skip_twin_of=skip)
                    if light_junction:
                        d_b -= emit / self.light_paths
                    fix = d_a / (d_a - dep) if (a is not None and dep > 0) else 1.0
                    coefficient = RHO[c] * P[c].get(j, 0.0) * fix / d_b
                    if target is None:
                        direct += coefficient * const
                    else:
                        pairs.append((target, coefficient))
            rows.append((emitted, direct, pairs))
        return rows

    def pixels(self, max_segments, twin_pair):
        rows = self.rows(twin_pair)
        l = [r[0] for r in rows]
        for _ in range(max_segments - 1):
            l = [e + dr + sum(cf * l[t] for t, cf in pr) for (e, dr, pr) in rows]
        return [l[f] for f in self.first]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--passes", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--pixels", type=int, default=40)
    ap.add_argument("--light-paths", type=int, default=40)
    ap.add_argument("--segments", type=int, default=12)
    ap.add_argument("--variant", nargs="+", default=["mvf", "before", "twins", "twins-pair"])
    args = ap.parse_args()
    ref = exact(args.segments)
    print(f"world: {CELLS} cells and a light, {args.pixels} camera paths and {args.light_paths} light paths per pass, "
          f"at most {args.segments} segments, {args.passes} passes, seed {args.seed}; exact pixel mean {ref:.6f}")
    for variant in args.variant:
        rng = random.Random(args.seed)
        lp = 0 if variant == "mvf" else args.light_paths
        twins = variant.startswith("twins")
        twin_pair = variant == "twins-pair"
        means = []
        for _ in range(args.passes):
            p = Pass(rng, args.pixels, lp, args.segments, twins)
            px = p.pixels(args.segments, twin_pair)
            means.append(sum(px) / len(px))
        n = len(means)
        m = sum(means) / n
        se = (sum((x - m) ** 2 for x in means) / (n - 1) / n) ** 0.5
        print(f"{variant:13s} mean / exact {m / ref:.4f} ± {se / ref:.4f}  (z {(m - ref) / se:+.1f})")


if __name__ == "__main__":
    main()
