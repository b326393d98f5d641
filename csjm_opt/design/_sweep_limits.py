"""Size and value bounds of a sweep file, checked before anything is allocated."""


#: Most designs in one sweep (a 1e6-design sweep takes days on a workstation).
MAX_DESIGNS = 1_000_000
#: Most orientations sampled per design (the metrics hold a few arrays of this length per load).
MAX_ORIENTATIONS = 100_000
#: Most shaping poses per design (each solves a QP family).
MAX_SHAPING_POSES = 10_000
#: Most rows of ``loads.tau_ext``.
MAX_LOADS = 100
#: Largest magnitude of any number in a sweep file (parameters are m, deg, N, N/m, kg).
MAX_VALUE = 1e9
#: Largest seed (numpy's generators take any integer; this keeps it a 63-bit integer).
MAX_SEED = 2 ** 63 - 1
