"""The stress suite: hard cases checked against high-precision (mpmath) references."""
