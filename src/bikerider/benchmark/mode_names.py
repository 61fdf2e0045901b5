"""Mode names by continuation in speed, from where they are unambiguous.

Where the weave pair is a complex pair (above the speed ``v_d`` where it is born, on a usual
bicycle) the names follow from the eigenvalues at that one speed: the pair is ``weave``, the larger
real eigenvalue ``capsize``, the smaller ``castor``.  Below ``v_d`` all four are real, and which
two are the weave pair depends on which two merge at ``v_d``: the two largest for most bicycles,
but not for all (55 of 433 random valid bicycles, ``docs/dynamics.md``), so no rule at one speed
can say.
So the names are carried by continuation:

* the speeds ``c_1 < ... < c_m`` where two eigenvalues coincide (the positive roots of the
  discriminant of the characteristic polynomial, :meth:`WhippleModel.collision_speeds`) cut the
  speeds into segments; inside one, real eigenvalues keep their order (two real eigenvalues of a
  real matrix family meet only at such a speed) and complex pairs stay complex;
* the anchor, the highest segment with exactly one complex pair (on a usual bicycle the one that
  reaches infinite speed), is named at one speed by the rule above; without such a segment every
  segment takes the per-speed rules of :func:`bikerider.benchmark.mode_labels.label_modes`;
* from each segment to its neighbour, across ``c_i``: the eigenvalues just on either side of
  ``c_i`` are matched (the assignment of the 24 with the least total distance) and carry their
  names across, down from the anchor and up from it.  Two eigenvalues that form a complex pair
  carry one name: two real eigenvalues of different names that merge into a pair make it
  ``"other"`` (as the per-speed rules name a pair below both real roots), the pair's halves keep
  that name if it splits again, and a lone ``weave`` left by such a merger is ``"other"`` too.

The result, for each speed, is the four eigenvalues in the order ``weave (+imag), weave (-imag),
capsize, castor`` with a label each (``"other"`` where an eigenvalue has none of those names); the
same layout :func:`~bikerider.benchmark.mode_labels.label_modes` gives, so every caller reads it
the same way.  At a speed within rounding of a collision the structure there decides the segment.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from bikerider.benchmark.mode_labels import IMAGINARY_TOLERANCE, MODES, label_modes

_PERMUTATIONS = np.array(list(itertools.permutations(range(4))))
_STEPS = (1e-7, 1e-5, 1e-3)
"""Relative distances from a collision speed at which its two sides are compared, smallest first:
the first at which both sides have the structure of their segments is taken."""


def slots(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Canonical order ``(..., 4)`` of eigenvalues ``(..., 4)`` and the number of complex pairs.

    Complex pairs first (falling imaginary part of the upper member; each upper member followed by
    its conjugate), then the real eigenvalues by falling real part.  Inside a segment of speeds
    between two collisions, the eigenvalue in each slot is one mode.
    """
    values = np.asarray(values, dtype=complex)
    largest = np.abs(values).max(axis=-1, keepdims=True)
    imag = values.imag
    is_complex = np.abs(imag) > IMAGINARY_TOLERANCE * np.maximum(1.0, largest)
    pairs = (is_complex & (imag > 0)).sum(axis=-1)
    # keys, primary last: complex before real; then falling |imag| (a pair) or falling real part;
    # then the upper member of a pair before its conjugate
    size = np.where(is_complex, -np.abs(imag), -values.real)
    if values.size <= _FEW:  # numpy.lexsort: the same order, less overhead on a few rows
        return np.lexsort((np.where(imag > 0, 0, 1), size, np.where(is_complex, 0, 1)), axis=-1), pairs
    return _order(is_complex, size, imag > 0), pairs


_FEW = 4 * 8192
"""Up to this many eigenvalues :func:`slots` sorts with ``numpy.lexsort``, above with :func:`_order`."""


def _order(is_complex: np.ndarray, size: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """The stable order of four keys per row, primary first: complex before real, rising ``size``
    (NaN last), ``upper`` before not; the order ``numpy.lexsort`` gives, many times faster on short
    rows: each element's rank is counted from the six pairwise comparisons."""
    nan = np.isnan(size)
    rank = np.zeros(size.shape, dtype=np.intp)
    for i, j in itertools.combinations(range(4), 2):
        gi, gj, si, sj = is_complex[..., i], is_complex[..., j], size[..., i], size[..., j]
        ni, nj = nan[..., i], nan[..., j]
        same_size = (si == sj) | (ni & nj)
        smaller = (si < sj) | (~ni & nj)
        # i before j (i < j, so an exact tie keeps i first)
        first = (gi & ~gj) | ((gi == gj) & (smaller | (same_size & (upper[..., i] | ~upper[..., j]))))
        rank[..., j] += first
        rank[..., i] += ~first
    order = np.empty_like(rank)
    np.put_along_axis(order, rank, np.arange(4), axis=-1)
    return order


@dataclass(frozen=True)
class Naming:
    """Names of each slot (:func:`slots`) in each segment between collision speeds.

    ``edges`` are the collision speeds (increasing); segment ``k`` lies between ``edges[k - 1]`` and
    ``edges[k]`` (``0`` and ``inf`` at the ends); ``pairs[k]`` is its number of complex pairs and
    ``names[k]`` the name of each of its four slots (for a segment with two pairs, at the end it
    was entered from; :attr:`paths` carries them through it).
    """

    edges: np.ndarray
    pairs: tuple[int, ...]
    names: tuple[tuple[str, ...], ...]
    paths: dict
    """For a segment with two complex pairs (whose slot order may change inside it): the speeds,
    the eigenvalues tracked along it ``(k, 4)`` and the name of each tracked column."""


def _top_names(values: np.ndarray) -> tuple[int, tuple[str, ...]]:
    """The names of the slots at a speed of the highest segment."""
    order, pairs = slots(values)
    s = values[order]
    if pairs == 1:
        return 1, ("weave", "weave", "capsize", "castor")
    labelled, labels = label_modes(values[None, :])
    names = []
    for x in s:  # the per-speed rules, slot by slot
        k = int(np.argmin(np.abs(labelled[0] - x)))
        names.append(str(labels[0, k]))
    return int(pairs), tuple(names)


def _consistent(names: list[str], pairs: int) -> tuple[str, ...]:
    """One name per complex pair (a pair whose members carry different names is ``"other"``), and
    ``weave`` on two eigenvalues or none (a lone one is ``"other"``)."""
    names = list(names)
    for p in range(pairs):
        a, b = names[2 * p], names[2 * p + 1]
        if a != b:
            names[2 * p] = names[2 * p + 1] = "other"
    if names.count("weave") != 2:
        names = ["other" if x == "weave" else x for x in names]
    return tuple(names)


def naming_speeds(collisions, top_speed: float) -> np.ndarray:
    """The speeds :func:`naming` evaluates first: the middle of each segment, ``top_speed``, then
    each collision times ``1 + step`` and times ``1 - step`` for each of the steps."""
    edges = np.asarray(collisions, dtype=float)
    lows = np.concatenate([[0.0], edges[:-1]]) if edges.size else np.zeros(0)
    steps = np.array(_STEPS)
    above, below = edges[:, None] * (1 + steps), edges[:, None] * (1 - steps)
    return np.concatenate([0.5 * (lows + edges), [top_speed], above.ravel(), below.ravel()])


def naming(eigenvalues_at, collisions, top_speed: float, evaluated: np.ndarray | None = None) -> Naming:
    """Names of every segment, carried from the anchor segment (module docstring) to the others.

    Parameters
    ----------
    eigenvalues_at : callable
        Speeds ``(k,)`` to eigenvalues ``(k, 4)`` of one system.
    collisions : array_like
        Speeds where two eigenvalues may coincide, increasing (spurious ones do no harm: the names
        pass through them unchanged).
    top_speed : float
        A speed above every collision, in the highest segment.
    evaluated : numpy.ndarray, optional
        ``eigenvalues_at(naming_speeds(collisions, top_speed))`` if already computed (a batch
        evaluates those of several systems at once).
    """
    edges = np.asarray(collisions, dtype=float)
    m = edges.size
    steps = np.array(_STEPS)
    above_all, below_all = edges[:, None] * (1 + steps), edges[:, None] * (1 - steps)
    if evaluated is None:  # one evaluation for the samples and both sides of every collision at every step
        evaluated = eigenvalues_at(naming_speeds(edges, top_speed))
    sampled = evaluated[: m + 1]
    evaluated_order, evaluated_structure = slots(evaluated)  # each speed on its own: once for all
    pairs = [int(x) for x in evaluated_structure[: m + 1]]
    names: list[tuple[str, ...]] = [()] * (m + 1)
    paths: dict[int, tuple[np.ndarray, np.ndarray, tuple[str, ...]]] = {}
    ones = [k for k in range(m + 1) if pairs[k] == 1]
    if not ones:  # no segment with exactly one pair: the per-speed rules, segment by segment
        return Naming(edges, tuple(pairs), tuple(_top_names(sampled[k])[1] for k in range(m + 1)), {})
    anchor = ones[-1]
    names[anchor] = ("weave", "weave", "capsize", "castor")
    for i in list(range(anchor - 1, -1, -1)) + list(range(anchor, m)):
        downward = i < anchor  # across edges[i], from segment i + 1 to i, or from i to i + 1
        known, unknown = (i + 1, i) if downward else (i, i + 1)
        sides = (above_all[i], below_all[i]) if downward else (below_all[i], above_all[i])
        above_at = slice(m + 1 + i * steps.size, m + 1 + (i + 1) * steps.size)
        below_at = slice(m + 1 + (m + i) * steps.size, m + 1 + (m + i + 1) * steps.size)
        parts = (above_at, below_at) if downward else (below_at, above_at)
        around = np.concatenate([evaluated[x] for x in parts])
        order = np.concatenate([evaluated_order[x] for x in parts])
        structure = np.concatenate([evaluated_structure[x] for x in parts])
        ok = (structure[: steps.size] == pairs[known]) & (structure[steps.size :] == pairs[unknown])
        if not ok.any():  # the sides never matched the segments: per-speed rules there
            names[unknown] = _top_names(sampled[unknown])[1]
            continue
        j = int(np.nonzero(ok)[0][0])
        source = around[j][order[j]]
        target = around[steps.size + j][order[steps.size + j]]
        known_names = _names_near(names[known], paths.get(known), sides[0][j], source)
        cost = np.abs(source[_PERMUTATIONS] - target[None, :]).sum(axis=-1)
        best = _PERMUTATIONS[int(np.argmin(cost))]  # target slot k is the mode of source slot best[k]
        names[unknown] = _consistent([known_names[best[k]] for k in range(4)], pairs[unknown])
        if pairs[unknown] == 2:  # two pairs may swap their slot order inside the segment: track them
            start = sides[1][j]
            if downward:
                end = edges[i - 1] * (1 + 1e-7) if i > 0 else 0.0
            else:
                end = edges[i + 1] * (1 - 1e-7) if i + 1 < m else top_speed
            paths[unknown] = _path(eigenvalues_at, start, end, target, names[unknown])
    return Naming(edges, tuple(pairs), tuple(names), paths)


_PATH_SAMPLES = 120


def path_speeds(collisions, top_speed: float, evaluated: np.ndarray) -> list[np.ndarray]:
    """The speeds at which :func:`naming` will follow the eigenvalues through each segment with two
    complex pairs (:func:`_path`), given its first evaluations ``evaluated`` (at
    :func:`naming_speeds`), for the usual case that each collision's sides match their segments at
    the first step; so a batch can evaluate them all at once.  A speed list it does not predict is
    evaluated by :func:`naming` itself, so a wrong prediction costs time, never a name."""
    edges = np.asarray(collisions, dtype=float)
    m = edges.size
    steps = np.array(_STEPS)
    above_all, below_all = edges[:, None] * (1 + steps), edges[:, None] * (1 - steps)
    _, pairs = slots(evaluated[: m + 1])
    ones = np.nonzero(pairs == 1)[0]
    if not ones.size:
        return []
    anchor = int(ones[-1])
    out = []
    for unknown in np.nonzero(pairs == 2)[0]:
        if unknown < anchor:  # entered downward across edges[unknown]
            i = int(unknown)
            start, end = below_all[i][0], (edges[i - 1] * (1 + 1e-7) if i > 0 else 0.0)
        else:  # upward across edges[unknown - 1]
            i = int(unknown) - 1
            start, end = above_all[i][0], (edges[i + 1] * (1 - 1e-7) if i + 1 < m else top_speed)
        out.append(np.linspace(start, end, _PATH_SAMPLES))
    return out


def _path(eigenvalues_at, start: float, end: float, first: np.ndarray, first_names: tuple[str, ...]):
    """Eigenvalues followed by continuity from ``start`` to ``end`` through a segment with two
    complex pairs (``first``: those at ``start`` in slot order, named ``first_names``): speeds, the
    followed values ``(k, 4)`` (columns in the order of ``first``) and the column names.  Real
    eigenvalues keep their slots inside a segment; only the two pairs may change their order, so at
    each step the pairs keep the assignment that moves their upper members least."""
    speeds = np.linspace(start, end, _PATH_SAMPLES)
    values = eigenvalues_at(speeds)
    order, _ = slots(values)
    slotted = np.take_along_axis(values, order, axis=-1)
    slotted[0] = first
    # Step by step: the upper members (a, b) followed to speed k - 1 and those in slots 0 and 2 at k,
    # (x, y), are swapped at k when |a - y| + |b - x| < |a - x| + |b - y|.  With (p, q) the slots
    # 0 and 2 at k - 1, (a, b) is (p, q) or (q, p), so with cross = |p - y| + |q - x| and
    # straight = |p - x| + |q - y| the followed order at k is swapped iff cross < straight (not
    # swapped at k - 1) or straight < cross (swapped at k - 1): it flips each time cross < straight
    # and is reset to the slot order where neither is smaller (a tie or NaN), all speeds at once.
    p, q = slotted[:-1, 0], slotted[:-1, 2]
    x, y = slotted[1:, 0], slotted[1:, 2]
    cross = np.abs(p - y) + np.abs(q - x)
    straight = np.abs(p - x) + np.abs(q - y)
    flip = np.concatenate([[False], cross < straight])
    reset = np.concatenate([[True], ~(cross < straight) & ~(straight < cross)])
    count = np.cumsum(flip)
    last = np.maximum.accumulate(np.where(reset, np.arange(speeds.size), 0))
    swapped = (count - count[last]) % 2 == 1
    tracked = slotted.copy()
    tracked[swapped] = slotted[swapped][:, [2, 3, 0, 1]]
    return speeds, tracked, first_names


def _names_near(names: tuple[str, ...], path, speed: float, slotted: np.ndarray) -> tuple[str, ...]:
    """The names of the slots of ``slotted`` (eigenvalues at ``speed`` in slot order): the segment's
    names, or for a segment with a tracked path those of the path's columns they match."""
    if path is None:
        return names
    speeds, tracked, column_names = path
    row = tracked[int(np.argmin(np.abs(speeds - speed)))]
    cost = np.abs(row[_PERMUTATIONS] - slotted[None, :]).sum(axis=-1)
    best = _PERMUTATIONS[int(np.argmin(cost))]
    return tuple(column_names[best[k]] for k in range(4))


def apply(values: np.ndarray, speeds: np.ndarray, named: Naming) -> tuple[np.ndarray, np.ndarray]:
    """``values (n, 4)`` at ``speeds (n,)`` ordered weave(+), weave(-), capsize, castor by
    ``named``, with their labels (:data:`MODES` or ``"other"``)."""
    values = np.asarray(values, dtype=complex)
    order, pairs = slots(values)
    segment = np.searchsorted(named.edges, speeds, side="right")
    known = np.array(named.pairs)
    fits = known[segment] == pairs
    for step in (-1, 1):  # within rounding of a collision: the neighbouring segment that fits
        near = np.clip(segment + step, 0, known.size - 1)
        move = ~fits & (known[near] == pairs)
        segment = np.where(move, near, segment)
        fits |= move
    if fits.all():  # every row is named below
        out, labels = np.empty(values.shape, dtype=complex), np.empty(values.shape, dtype=object)
    else:  # where no segment fits: the per-speed rules
        out, labels = label_modes(values)
    s = np.take_along_axis(values, order, axis=-1)
    s = np.where(pairs[:, None] == 0, s.real, s)
    for seg in np.unique(segment[fits]):
        rows = np.nonzero(fits & (segment == seg))[0]
        path = named.paths.get(int(seg))
        if path is None:
            position, label = _arrange(named.names[seg])
            out[rows] = s[rows][:, position]
            labels[rows] = label
            continue
        # two complex pairs: each speed's names from the tracked path (:func:`_names_near`, all rows)
        path_speeds, tracked, column_names = path
        row = tracked[np.argmin(np.abs(path_speeds[None, :] - speeds[rows, None]), axis=1)]
        cost = np.abs(row[:, _PERMUTATIONS] - s[rows][:, None, :]).sum(axis=-1)
        best = _PERMUTATIONS[np.argmin(cost, axis=-1)]  # (rows, 4)
        code = best @ np.array([64, 16, 4, 1])
        for kind in np.unique(code):
            chosen = rows[code == kind]
            permutation = best[np.argmax(code == kind)]
            position, label = _arrange(tuple(column_names[permutation[k]] for k in range(4)))
            out[chosen] = s[chosen][:, position]
            labels[chosen] = label
    return out, labels


def _arrange(names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Which slot goes to each position of :data:`MODES` (``(4,)``, for slots named ``names``) and
    the label of each position."""
    label = np.array(["other"] * 4, dtype=object)
    position = np.zeros(4, dtype=np.intp)
    weave = [j for j in range(4) if names[j] == "weave"]
    slot_of: dict[int, int] = {}
    if len(weave) == 2:
        a, b = weave  # a pair's upper member comes first in slot order; two real roots: the larger first
        slot_of[0], slot_of[1] = a, b
    elif len(weave) == 1:
        slot_of[0] = weave[0]
    for mode_position, mode in ((2, "capsize"), (3, "castor")):
        match = [j for j in range(4) if names[j] == mode]
        if match:
            slot_of[mode_position] = match[0]
    taken = list(slot_of.values())
    free = [j for j in range(4) if j not in taken]
    for p in range(4):
        if p in slot_of:
            position[p] = slot_of[p]
            label[p] = MODES[p]
        else:
            position[p] = free.pop(0)
    return position, label


__all__ = ["Naming", "apply", "naming", "naming_speeds", "path_speeds", "slots"]


# -- a batch of bicycles at once ------------------------------------------------------------------
CODES = ("weave", "capsize", "castor", "other")
"""Name codes of the batched path."""
_OTHER = 3


def _consistent_codes(names: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """:func:`_consistent` on codes ``(b, 4)`` with ``pairs`` ``(b,)``."""
    names = names.copy()
    for p in range(2):
        mixed = (p < pairs) & (names[:, 2 * p] != names[:, 2 * p + 1])
        names[mixed, 2 * p] = names[mixed, 2 * p + 1] = _OTHER
    lone = (names == 0).sum(axis=1) != 2
    names[lone] = np.where(names[lone] == 0, _OTHER, names[lone])
    return names


def batch_naming(eigenvalues_at, edges: np.ndarray, top: np.ndarray):
    """:func:`naming` for ``b`` systems at once, where they need no per-system treatment.

    Parameters
    ----------
    eigenvalues_at : callable
        Speeds ``(b, k)`` to eigenvalues ``(b, k, 4)`` (each system at its own speeds); with a
        second argument, an index array of systems, speeds ``(len(index), k)`` of those.
    edges : numpy.ndarray, shape (b, m)
        Each system's collision speeds, increasing, NaN-padded.
    top : numpy.ndarray, shape (b,)
        A speed above each system's collisions.

    Returns
    -------
    pairs : numpy.ndarray of int, shape (b, m + 1)
        Complex pairs of each segment (segments past a system's last edge repeat its top one).
    names : numpy.ndarray of int, shape (b, m + 1, 4)
        Each segment's slot names as :data:`CODES`.
    alone : numpy.ndarray of bool, shape (b,)
        Systems the batch does not decide (no segment with one pair, a segment with two, sides of
        a collision that never match their segments): name them one by one with :func:`naming`.
    """
    b, m = edges.shape
    count = np.isfinite(edges).sum(axis=1)
    k = np.arange(m + 1)
    lows = np.concatenate([np.zeros((b, 1)), edges], axis=1)[:, :m]
    mids = 0.5 * (lows + edges)
    samples = np.where(k[None, :m] < count[:, None], mids, top[:, None])
    samples = np.concatenate([samples, top[:, None]], axis=1)
    c = np.where(np.isfinite(edges), edges, top[:, None])
    # one evaluation for the segments' samples and both sides of each collision at the first step
    # (each speed's eigenvalues do not depend on the others evaluated with it)
    wanted = np.concatenate([samples, c * (1 + _STEPS[0]), c * (1 - _STEPS[0])], axis=1)
    # only the speeds in use (a system's own segments and collisions; the rest of the padded table
    # takes the values at ``top``, its highest segment's sample), each speed on its own
    own = k[None, :m] < count[:, None]
    used = np.concatenate([own, np.ones((b, 1), dtype=bool), own, own], axis=1)
    system, column = np.nonzero(used)
    evaluated = np.empty(wanted.shape + (4,), dtype=complex)
    if system.size:
        evaluated[system, column] = eigenvalues_at(wanted[system, column][:, None], system)[:, 0]
    evaluated[~used] = np.broadcast_to(evaluated[:, m : m + 1], evaluated.shape)[~used]
    evaluated_order, evaluated_pairs = slots(evaluated)
    pairs = evaluated_pairs[:, : m + 1]
    in_range = k[None, :] <= count[:, None]
    alone = np.any(in_range & (pairs == 2), axis=1)
    ones = np.where(in_range & (pairs == 1), k[None, :], -1)
    anchor = ones.max(axis=1)
    alone |= anchor < 0
    names = np.full((b, m + 1, 4), _OTHER, dtype=np.int8)
    rows = np.arange(b)
    names[rows, np.maximum(anchor, 0)] = np.array([0, 0, 1, 2], dtype=np.int8)
    if m == 0:
        return pairs, names, alone
    # downward across edge i (i < anchor): known segment i + 1 (above), unknown i (below); upward
    # (anchor <= i < count): known i (below), unknown i + 1 (above)
    down = k[None, :m] < anchor[:, None]
    up = (k[None, :m] >= anchor[:, None]) & (k[None, :m] < count[:, None])
    known_pairs = np.where(down, pairs[:, 1:], pairs[:, :m])
    unknown_pairs = np.where(down, pairs[:, :m], pairs[:, 1:])
    source = np.zeros((b, m, 4), dtype=complex)
    target = np.zeros((b, m, 4), dtype=complex)
    pending = down | up
    for s, step in enumerate(_STEPS):  # the smallest step at which both sides have their segments' structure
        rows_pending = np.nonzero(pending.any(axis=1))[0]
        if not rows_pending.size:
            break
        if s == 0:  # evaluated above
            around = evaluated[rows_pending, m + 1 :]
            order, structure = evaluated_order[rows_pending, m + 1 :], evaluated_pairs[rows_pending, m + 1 :]
        else:
            cc = c[rows_pending]
            around = eigenvalues_at(np.concatenate([cc * (1 + step), cc * (1 - step)], axis=1), rows_pending)
            order, structure = slots(around)
        slotted = np.take_along_axis(around, order, axis=-1)
        above, below = slotted[:, :m], slotted[:, m:]
        d = down[rows_pending]
        known_side = np.where(d, structure[:, :m], structure[:, m:])
        unknown_side = np.where(d, structure[:, m:], structure[:, :m])
        ok = pending[rows_pending] & (known_side == known_pairs[rows_pending])
        ok &= unknown_side == unknown_pairs[rows_pending]
        r, e = np.nonzero(ok)
        rows_ok = rows_pending[r]
        source[rows_ok, e] = np.where(d[r, e, None], above[r, e], below[r, e])
        target[rows_ok, e] = np.where(d[r, e, None], below[r, e], above[r, e])
        pending[rows_ok, e] = False
    alone |= pending.any(axis=1)
    cost = np.abs(source[:, :, _PERMUTATIONS] - target[:, :, None, :]).sum(axis=-1)  # (b, m, 24)
    best = _PERMUTATIONS[np.argmin(cost, axis=-1)]  # (b, m, 4)
    for i in range(m - 1, -1, -1):  # down from each anchor
        sel = down[:, i]
        if sel.any():
            carried = np.take_along_axis(names[sel, i + 1], best[sel, i], axis=-1)
            names[sel, i] = _consistent_codes(carried, pairs[sel, i])
    for i in range(m):  # and up
        sel = up[:, i]
        if sel.any():
            carried = np.take_along_axis(names[sel, i], best[sel, i], axis=-1)
            names[sel, i + 1] = _consistent_codes(carried, pairs[sel, i + 1])
    names[:, 1:] = np.where(k[None, 1:, None] > count[:, None, None], names[rows, count][:, None], names[:, 1:])
    return pairs, names, alone


def batch_apply(values: np.ndarray, speeds: np.ndarray, edges: np.ndarray, pairs: np.ndarray, names: np.ndarray):
    """:func:`apply` for ``b`` systems: ``values (b, n, 4)`` at ``speeds (n,)``, named by
    :func:`batch_naming`'s ``pairs`` and ``names``; the values in :data:`MODES` order and labels."""
    b, n, _ = values.shape
    order, row_pairs = slots(values)
    finite = np.isfinite(edges)
    segment = np.zeros((b, n), dtype=np.intp)  # (b, n): the collisions at or below each speed (NaN: never)
    for column in edges.T:
        segment += column[:, None] <= speeds[None, :]
    last = pairs.shape[1] - 1
    known = np.take_along_axis(pairs, segment, axis=1)
    fits = known == row_pairs
    for step in (-1, 1):
        near = np.clip(segment + step, 0, np.minimum(finite.sum(axis=1), last)[:, None])
        move = ~fits & (np.take_along_axis(pairs, near, axis=1) == row_pairs)
        segment = np.where(move, near, segment)
        fits |= move
    segment_key = (names.astype(np.int64) * np.array([64, 16, 4, 1])).sum(axis=-1)  # (b, m + 1): names as one code
    key = np.take_along_axis(segment_key, segment, axis=1)  # (b, n): each row's segment's names
    codes = np.flatnonzero(np.bincount(key.reshape(-1), minlength=256))  # the codes present, no sort
    lookup = np.zeros(256, dtype=np.intp)
    lookup[codes] = np.arange(codes.size)
    which = lookup[key]
    # each code's arrangement (which slot goes to each position) and labels, then all rows at once
    arranged = [_arrange(tuple(CODES[(int(c) >> shift) & 3] for shift in (6, 4, 2, 0))) for c in codes]
    position = np.array([p for p, _ in arranged], dtype=np.intp).reshape(codes.size, 4)
    label = np.array([x for _, x in arranged], dtype=object).reshape(codes.size, 4)
    index = np.take_along_axis(order, position[which], axis=-1)
    out = np.take_along_axis(values, index, axis=-1)
    out.imag[row_pairs == 0] = 0.0  # four real eigenvalues: no rounding residue in the imaginary parts
    labels = label[which]
    if not fits.all():  # within rounding of a collision no segment fits: the per-speed rules
        out[~fits], labels[~fits] = label_modes(values[~fits])
    return out, labels


__all__ += ["CODES", "batch_apply", "batch_naming"]
