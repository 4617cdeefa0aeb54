"""The multi-objective adversarial gesture model of Ferstl, Neff and McDonnell (MIG 2019), re-implemented
from the paper (no code was published): networks and staged training on arrays."""
