"""The watch: the requested conditioning metrics of M(q) at sample times, in any loop.

One public entry, [`Watch`][gimwatch.watch.watch.Watch]: built on a gimwatch robot
(``Watch(robot, ...)``), a Pinocchio model (``Watch.from_model``), a MuJoCo model and data
(``Watch.from_mujoco``) or matrices handed in (``Watch.from_matrices``). Inside the family:
`watch` (sampling, only the metrics asked for), `sources` (where M(q) comes from and the
checks on it), `alarm` (upward crossings of a threshold and their warning) and `series` (the
recorded samples, growing arrays).
"""

from gimwatch.watch.alarm import DEFAULT_ALARM_THRESHOLD, Alarm
from gimwatch.watch.watch import Watch

__all__ = ["DEFAULT_ALARM_THRESHOLD", "Alarm", "Watch"]
