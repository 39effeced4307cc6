#!/usr/bin/env python3
"""bench/partial-frame.py REF.pfm A.pfm B.pfm (session 42, issue #14).

What a second frame over part of the image would buy. A and B are two 1-spp images
of other seeds (clvr --spp 1 --seed 1 / --seed 2), REF a many-sample reference. It prints
the relative RMSE (over the pixels that differ from the background in REF, divided by
their mean; REF's own noise not subtracted) of A alone, of (A + B) / 2 everywhere, and of
(A + B) / 2 on a fraction of the pixels only, chosen
  (a) by the spread of the 8 neighbours' A values (the pixel's own value is not read,
      so its estimate stays unbiased), or
  (b) at random.
(A + B) / 2 of two finished images understates what the renderer's own second frame
does (its pixel control variates fit the accumulated image, and the ld sampler
stratifies the two frames). (Its figures before session 46, "the combustor's 2-spp image
is at 1.13%, not 1.43%", summed the error over every pixel; now over the inside ones.)
"""
import math, os, random, sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'tests'))
from checklib import read_pfm  # noqa: E402 (the tests' PFM reader)


def lum(d, i):
    return (d[3 * i] + d[3 * i + 1] + d[3 * i + 2]) / 3.0


ref_p, a_p, b_p = sys.argv[1:4]
w, h, ref = read_pfm(ref_p)
_, _, a = read_pfm(a_p)
_, _, b = read_pfm(b_p)
bg = ref[0:3]
inside = [i for i in range(w * h) if any(abs(ref[3 * i + k] - bg[k]) > 1e-6 for k in range(3))]
inside_set = set(inside)
mean = sum(sum(ref[3 * i:3 * i + 3]) / 3 for i in inside) / len(inside)


def rmse(pick):
    # Over the inside pixels, as the docstring says and bench_render does (it
    # summed over every pixel, which understated the error by the square
    # root of the inside fraction: 0.40x on the notch at 256x256).
    s = 0.0
    for i in inside:
        for k in range(3):
            v = 0.5 * (a[3 * i + k] + b[3 * i + k]) if pick[i] else a[3 * i + k]
            s += (v - ref[3 * i + k]) ** 2
    return math.sqrt(s / (3 * len(inside))) / mean


def spread(i):
    x, y = i % w, i // w
    vals = [lum(a, yy * w + xx) for yy in range(y - 1, y + 2) for xx in range(x - 1, x + 2)
            if (xx, yy) != (x, y) and 0 <= xx < w and 0 <= yy < h]
    m = sum(vals) / len(vals)
    return sum((v - m) ** 2 for v in vals) / len(vals)


print(f"{len(inside)} pixels inside, reference mean {mean:.4f}")
print(f"1 frame: {100 * rmse([0] * (w * h)):.3f}%  2 frames: {100 * rmse([1] * (w * h)):.3f}%")
order = sorted(inside, key=spread, reverse=True)  # the inside pixels, as the random pick
rnd = list(range(w * h))
random.Random(1).shuffle(rnd)
rnd_inside = [i for i in rnd if i in inside_set]
for frac in (0.1, 0.2, 0.3, 0.5, 0.7):
    n = int(frac * len(inside))
    pick_s = [0] * (w * h)
    for i in order[:n]:
        pick_s[i] = 1
    pick_r = [0] * (w * h)
    for i in rnd_inside[:n]:
        pick_r[i] = 1
    print(f"second frame on {frac:.0%} of the inside pixels: by neighbour spread {100 * rmse(pick_s):.3f}%, "
          f"at random {100 * rmse(pick_r):.3f}%")
