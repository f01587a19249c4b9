"""Limits of a run that every layer may read (the model checks a scene against them, the
history engines size their tables by them)."""

#: threads of the FFTs or of the engine's loop, at most
MAX_FFT_THREADS = 1024
#: t_end / dt: more steps than this is refused before any work
MAX_STEPS = 10**8
#: snapshots of a run, at most
MAX_SNAPSHOTS = 10**7
