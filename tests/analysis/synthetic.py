"""Seeded synthetic signals with known spectral answers, generated many at once (one row per
trial): AR(2) noise resonances, impulse trains periodic with T or with 2T, trains of
Hertz-like pulses, low-pass noise.  Used by tests/analysis and benchmarks/line_detection.py.

Every signal: 2 s at 10 kHz unless told (the paper scenario's windows and sample rate).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

FS = 10_000.0  # Hz
DURATION = 2.0  # s
TIME = np.arange(round(FS * DURATION)) / FS
#: The paper scenario at 830 rpm: mesh frequency (z_p = 20) and the forcing's fundamental
#: (engine order 2: the period of orders 2, 4, 6 and of the mesh).
F_MESH = 20 * 830.0 / 60.0
F_FORCING = 2 * 830.0 / 60.0


def ar2_noise(rows: int, f_r: float, q: float, rng, n: int = TIME.size) -> np.ndarray:
    """Gaussian noise through a two-pole resonator at ``f_r`` [Hz] with quality factor ``q``
    (poles at radius r = 1 - pi f_r / (q FS): a -3 dB bandwidth of f_r / q)."""
    r = 1.0 - math.pi * f_r / (q * FS)
    a = [1.0, -2.0 * r * math.cos(2.0 * math.pi * f_r / FS), r * r]
    return signal.lfilter([1.0], a, rng.standard_normal((rows, n)), axis=1)


def lowpass_noise(rows: int, cutoff: float, rng, order: int = 4) -> np.ndarray:
    """White noise through a Butterworth low-pass: its PSD falls 10 dB below the pass band at
    ``cutoff * 9 ** (1 / (2 order))`` (1316 Hz for order 4 at 1 kHz)."""
    b, a = signal.butter(order, cutoff, fs=FS)
    return signal.lfilter(b, a, rng.standard_normal((rows, TIME.size)), axis=1)


def lowpass_ten_db(cutoff: float, order: int = 4) -> float:
    """Frequency [Hz] where the Butterworth low-pass's power is 10 dB below its pass band."""
    return cutoff * 9.0 ** (1.0 / (2 * order))


def impulse_train(rows: int, rng, period: float, phases=(0.0,), amplitudes=(1.0,),
                  odd_phases=None, odd_amplitudes=None, jitter: float = 0.0,
                  amplitude_sd: float = 0.0, noise: float = 0.0,
                  pulse: tuple[float, float] = (0.3e-3, 0.3e-3)) -> np.ndarray:
    """Trains of Hertz-like pulses (sin^1.5 half waves, sampled in continuous time).

    Each ``period`` [s] holds one pulse per entry of ``phases`` (fractions of the period)
    with the matching ``amplitudes``; with ``odd_phases`` / ``odd_amplitudes`` every second
    period uses those instead, so the train repeats only every 2 periods (a sub-harmonic at
    (k + 1/2) / period).  Every pulse is moved by Gaussian ``jitter`` [s], its amplitude
    scaled by (1 + ``amplitude_sd`` N(0, 1)), its duration drawn uniformly from ``pulse``
    [s]; white noise of standard deviation ``noise`` is added.  Each row starts at a random
    point of the pattern."""
    phases, amplitudes = np.asarray(phases, float), np.asarray(amplitudes, float)
    odd_p = phases if odd_phases is None else np.asarray(odd_phases, float)
    odd_a = amplitudes if odd_amplitudes is None else np.asarray(odd_amplitudes, float)
    n = TIME.size
    cycles = np.arange(-1, int(DURATION / period) + 2)
    odd = (cycles % 2 == 1)[:, None]
    t = (cycles[:, None] + np.where(odd, odd_p, phases)) * period  # cycles x pulses
    a = np.where(odd, odd_a, amplitudes) * np.ones_like(t)
    t, a = t.ravel(), a.ravel()
    m = t.size
    start = rng.uniform(0.0, 2.0 * period, (rows, 1))
    times = t[None, :] - start + jitter * rng.standard_normal((rows, m))
    amps = a[None, :] * (1.0 + amplitude_sd * rng.standard_normal((rows, m)))
    dur = rng.uniform(pulse[0], pulse[1], (rows, m))
    out = np.zeros(rows * n)
    first = np.ceil(times * FS).astype(int)
    offset = np.arange(rows)[:, None] * n
    for j in range(math.ceil(pulse[1] * FS) + 1):
        idx = first + j
        tau = idx / FS - times
        ok = (idx >= 0) & (idx < n) & (tau >= 0) & (tau < dur)
        np.add.at(out, (idx + offset)[ok],
                  amps[ok] * np.sin(np.pi * tau[ok] / dur[ok]) ** 1.5)
    x = out.reshape(rows, n)
    if noise:
        x = x + noise * rng.standard_normal((rows, n))
    return x


#: A mesh-rate train: one impact per mesh period, 3 % timing jitter, 30 % amplitude scatter,
#: 0.2-0.4 ms pulses, white noise; the 2T variant alternates the amplitude by +-20 % (its
#: sub-harmonic comb is (0.2)^2, -14 dB, of the comb at low harmonics).
MESH_TRAIN = dict(period=1.0 / F_MESH, jitter=0.03 / F_MESH, amplitude_sd=0.3, noise=0.3,
                  pulse=(0.2e-3, 0.4e-3))
MESH_TRAIN_2T = dict(MESH_TRAIN, amplitudes=(1.2,), odd_amplitudes=(0.8,))
#: An engine-cycle pattern like the paper scenario's: six impacts per forcing period (order 2,
#: 36 ms) at fixed, uneven phases and strengths, 0.1 ms jitter, 10 % amplitude scatter, white
#: noise; the 2T variant changes two of the six impacts in every second cycle (one 0.5 ms
#: later, one 25 % weaker), as a period doubling of the rattle pattern would.
CYCLE_PHASES = (0.03, 0.19, 0.31, 0.52, 0.66, 0.85)
CYCLE_AMPLITUDES = (1.0, 0.6, 0.8, 0.5, 0.9, 0.7)
CYCLE_TRAIN = dict(period=1.0 / F_FORCING, phases=CYCLE_PHASES, amplitudes=CYCLE_AMPLITUDES,
                   jitter=0.1e-3, amplitude_sd=0.1, noise=0.05, pulse=(0.2e-3, 0.4e-3))


def cycle_train_2t(shift: float = 0.5e-3, weaker: float = 0.75) -> dict:
    """CYCLE_TRAIN with every second cycle's third impact ``shift`` [s] later and its fifth
    ``weaker`` times as strong."""
    return dict(CYCLE_TRAIN,
                odd_phases=tuple(p + (shift * F_FORCING if i == 2 else 0.0)
                                 for i, p in enumerate(CYCLE_PHASES)),
                odd_amplitudes=tuple(a * (weaker if i == 4 else 1.0)
                                     for i, a in enumerate(CYCLE_AMPLITUDES)))


CYCLE_TRAIN_2T = cycle_train_2t()
