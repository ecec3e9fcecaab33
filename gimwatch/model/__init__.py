"""From a robot specification to a model: URDF checks, generated rod chains, robots, the GIM."""
