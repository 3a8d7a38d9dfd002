"""Random streams: one seeded, independent noise source per named consumer.

A lab (or a campaign trial) has one seed. Each consumer of randomness (an instrument, a robot
loading a workpiece) draws from its own stream, derived from the seed and the consumer's name
through `numpy.random.SeedSequence`'s spawn keys. So a consumer's draws depend only on
(seed, name): adding, removing or reordering another consumer's readings changes nothing
here, and two names never share a stream.

>>> a = stream(7, "microscope", "calibration").standard_normal(2)
>>> b = stream(7, "microscope", "calibration").standard_normal(2)
>>> bool((a == b).all())
True
"""

from __future__ import annotations

import zlib

import numpy as np

from machinesim.exceptions import InputError

__all__ = ["stream", "stream_key"]


def stream_key(*names) -> tuple[int, ...]:
    """Spawn key of a consumer: each name (str or int) as a stable 32-bit integer.

    Strings go through CRC-32, which, unlike Python's ``hash``, is the same in every process
    (a worker of a campaign derives the same stream as the client).
    """
    key = []
    for name in names:
        if isinstance(name, str):
            key.append(zlib.crc32(name.encode()))
        elif isinstance(name, int | np.integer) and not isinstance(name, bool) and name >= 0:
            key.append(int(name))
        else:
            raise InputError(f"Expected stream names as strings or non-negative ints, got "
                             f"{name!r}", key="names")
    return tuple(key)


def stream(seed, *names) -> np.random.Generator:
    """The generator of consumer ``names`` under ``seed``.

    Parameters
    ----------
    seed : int or numpy.random.SeedSequence
        The lab's (or trial's) seed; a SeedSequence keeps its own spawn key as a prefix.
    *names : str or int
        Who draws, e.g. ``("microscope", "calibration")``.
    """
    if isinstance(seed, np.random.SeedSequence):
        base = seed
    elif isinstance(seed, int | np.integer) and not isinstance(seed, bool) and seed >= 0:
        base = np.random.SeedSequence(int(seed))
    else:
        raise InputError(f"Expected a seed as a non-negative int or a SeedSequence, got "
                         f"{seed!r}", key="seed")
    sequence = np.random.SeedSequence(base.entropy,
                                      spawn_key=tuple(base.spawn_key) + stream_key(*names))
    return np.random.default_rng(sequence)
