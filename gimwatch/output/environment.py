"""Where a result was computed: library versions and the CPU, for report headers."""

from __future__ import annotations

import os
import platform

__all__ = ["cpu_model", "versions"]


def versions() -> dict[str, str]:
    """Versions of gimwatch, Python and the libraries a result depends on."""
    import matplotlib
    import numpy
    import pinocchio
    import scipy

    from gimwatch._version import __version__

    return {
        "gimwatch": __version__,
        "python": platform.python_version(),
        "pinocchio": pinocchio.__version__,
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "matplotlib": matplotlib.__version__,
    }


def cpu_model() -> str:
    """The CPU's model name (from /proc/cpuinfo on Linux) and the number of logical cores."""
    name = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as handle:
            for line in handle:
                if line.startswith("model name"):
                    name = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{name} ({os.cpu_count()} logical cores)"
