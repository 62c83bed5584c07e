"""
Measurements of the natural mirrors (docs/natural.md): the disorder estimator's error, the spectral fit's
round trip, and the costs. ``python3 -m explorer.dev.natural_studies [--quick]`` prints Markdown.

- Disorder: :func:`explorer.physics.natural.mirror_spectrum` (``REALISATIONS`` scrambled-Sobol realisations,
  seeded) against the mean of ``REFERENCE_DRAWS`` independent pseudo-random realisations (truncation by
  rejection), per wavelength; the reference's own standard error is printed beside it.
- Fit: seeded random absorbing, dispersive mirrors (chitin under air with a second layer of index 1.6-1.9,
  k2 in [0, 0.1], Lambda 150-400 nm, delta 0.2-0.8, N 3-15; keratin over melanin; the first with sigma = 0.1)
  fitted from their own spectra at 0 degrees, the media (and sigma) fixed.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from explorer.physics import dispersion, multilayer
from explorer.physics.natural import NaturalMirror, mirror_spectrum
from explorer.physics.spectral_fit import fit_spectrum

REFERENCE_DRAWS = 32768


def _reference_mean(mirror: NaturalMirror, wavelengths: np.ndarray, theta: float, draws: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    base = np.array([mirror.d2, mirror.d1] * mirror.N)
    eps = rng.standard_normal((draws, base.size))
    while np.any(np.abs(eps) > multilayer.TRUNCATION):
        bad = np.abs(eps) > multilayer.TRUNCATION
        eps[bad] = rng.standard_normal(int(bad.sum()))
    host, indices, _, sub = mirror.layer_stack(wavelengths)
    thick = base * (1.0 + mirror.sigma * eps)
    sin = np.sin(np.radians(theta))
    samples = 0.0
    for pol in ("s", "p"):
        block = []
        for start in range(0, draws, 512):
            block.append(multilayer.stack_optics(pol, host, indices, thick[start:start + 512], sub, wavelengths, sin).R)
        samples = samples + 0.5 * np.concatenate(block)
    return samples.mean(axis=0), samples.std(axis=0, ddof=1) / np.sqrt(draws)


def disorder_rows(draws: int) -> list[str]:
    chitin = dispersion.LIBRARY["chitin"]
    cases = [("chitin/air, N 10, sigma 0.1", NaturalMirror(n1=1.0, n2=chitin, k2=0.02, Lambda=250.0, N=10, nh=1.0, sigma=0.1)),
             ("chitin/air, N 20, sigma 0.05", NaturalMirror(n1=1.0, n2=chitin, Lambda=250.0, N=20, nh=1.0, sigma=0.05)),
             ("melanin/keratin, N 6, sigma 0.3", NaturalMirror(n1=dispersion.LIBRARY["keratin"], n2=dispersion.LIBRARY["melanin"],
                                                              Lambda=300.0, N=6, nh=1.0, sigma=0.3))]
    wavelengths = np.linspace(400.0, 700.0, 31)
    rows = ["| mirror | θ | max abs error | median abs error | reference SE (median) | seconds (31 wavelengths) |",
            "|---|---|---|---|---|---|"]
    for name, mirror in cases:
        for theta in (0.0, 45.0):
            start = time.perf_counter()
            ours = mirror_spectrum(mirror, wavelengths, [theta])["R"][0]
            seconds = time.perf_counter() - start
            mean, se = _reference_mean(mirror, wavelengths, theta, draws)
            error = np.abs(ours - mean)
            rows.append(f"| {name} | {theta:g}° | {error.max():.4f} | {np.median(error):.4f} | {np.median(se):.4f} | {seconds:.2f} |")
    return rows


#: The fit's families: the media fixed, the truth's draws (the rest free unless ``fixed``).
FIT_FAMILIES = {
    "chitin, absorbing n2": ({"n1": "chitin"}, {"nh": 1.0}),
    "keratin over melanin": ({"n1": "keratin", "n2": "melanin"}, {"nh": 1.0}),
    "chitin, absorbing n2, sigma 0.1": ({"n1": "chitin"}, {"nh": 1.0, "sigma": 0.1}),
}


def fit_rows(count: int, families=tuple(FIT_FAMILIES)) -> list[str]:
    wavelengths = np.arange(380.0, 801.0, 5.0)
    rows = ["| mirrors | median RMS | 90th percentile | max | within 0.01 | median seconds |", "|---|---|---|---|---|---|"]
    for family in families:
        names, numbers = FIT_FAMILIES[family]
        media = {k: dispersion.LIBRARY[v] for k, v in names.items()}
        rng = np.random.default_rng(35)
        rms, seconds = [], []
        for _ in range(count):
            draw = dict(n2=float(rng.uniform(1.6, 1.9)), k2=float(rng.uniform(0.0, 0.1)), Lambda=float(rng.uniform(150.0, 400.0)),
                        delta=float(rng.uniform(0.2, 0.8)), N=int(rng.integers(3, 16)))
            if "n2" in media:
                draw.pop("n2"), draw.pop("k2")
            truth = NaturalMirror(**{**draw, **media, **numbers})
            R = mirror_spectrum(truth, wavelengths, [0.0])["R"][0]
            fit = fit_spectrum(wavelengths, R, 0.0, {**media, **numbers})
            rms.append(fit.rms)
            seconds.append(fit.seconds)
        rms = np.array(rms)
        rows.append(f"| {family}: {count} | {np.median(rms):.2e} | {np.percentile(rms, 90):.2e} | {rms.max():.2e} | "
                    f"{np.mean(rms <= 0.01):.0%} | {np.median(seconds):.1f} |")
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--quick", action="store_true", help="4,096 reference draws and 5 fits (else 32,768 and 20)")
    parser.add_argument("--fits-only", action="store_true", help="only the fits")
    args = parser.parse_args(argv)
    if args.fits_only:
        print("\n".join(fit_rows(5 if args.quick else 20)))
        return
    draws, fits = (4096, 5) if args.quick else (REFERENCE_DRAWS, 20)
    print(f"### Disorder: {multilayer.REALISATIONS} seeded Sobol realisations against {draws} independent draws\n")
    print("\n".join(disorder_rows(draws)))
    print("\n### Fit: random absorbing, dispersive mirrors from their own spectra (380-800 nm every 5 nm)\n")
    print("\n".join(fit_rows(fits)))


if __name__ == "__main__":
    main()
