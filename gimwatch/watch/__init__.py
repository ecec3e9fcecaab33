"""The watch: the requested conditioning metrics of M(q) at sample times, in any loop.

One public entry, [`Watch`][gimwatch.watch.watch.Watch]: built on a gimwatch robot
(``Watch(robot, ...)``), a Pinocchio model (``Watch.from_model``), a MuJoCo model and data
(``Watch.from_mujoco``), matrices handed in (``Watch.from_matrices``) or any
``MassMatrixSource`` (``Watch(source=...)``). Inside the family: `watch` (sampling, only the
metrics asked for), `sources` (MuJoCo's M and a matrix in hand, and the checks on them),
`compiled_path` (the compiled sampler of κ and δ) with its `kernels` and `spectrum_solver`,
`alarm` (upward crossings of a threshold and their warning), `series` (the recorded samples,
growing arrays) and `series_views` (arrays, frames and figures of them).
"""

from gimwatch.watch.alarm import DEFAULT_ALARM_THRESHOLD, Alarm
from gimwatch.watch.watch import Watch

__all__ = ["DEFAULT_ALARM_THRESHOLD", "Alarm", "Watch"]
