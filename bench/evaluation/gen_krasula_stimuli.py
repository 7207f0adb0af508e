#!/usr/bin/env python3
"""A synthetic subjective table for the Krasula benchmark of `qm3d eval`.

    gen_krasula_stimuli.py N OUT.csv [SEED]

N stimuli (10,000 gives 49,995,000 pairs), one row each: stimulus, MOS (1..5), SD, n
(observers) and two metric columns, m1 (MOS plus noise) and m2 (a coarser, noisier one with
ties), so that the analysis sees different and similar pairs, ties and zero differences. The
same N and seed give the same file (Python's own generator, no numpy needed).
"""
import random
import sys


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    count, out = int(sys.argv[1]), sys.argv[2]
    rng = random.Random(int(sys.argv[3]) if len(sys.argv) == 4 else 37)
    with open(out, "w") as f:
        f.write("stimulus,MOS,SD,n,m1,m2\n")
        for i in range(count):
            mos = rng.uniform(1, 5)
            sd = rng.uniform(0.3, 1.2)
            n = rng.randint(12, 30)
            m1 = mos + rng.gauss(0, 0.4)
            m2 = round((mos + rng.gauss(0, 0.8)) * 4) / 4
            f.write("s%d,%.6f,%.6f,%d,%.9f,%.2f\n" % (i, mos, sd, n, m1, m2))


if __name__ == "__main__":
    main()
