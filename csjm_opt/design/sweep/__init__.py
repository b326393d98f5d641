"""Design sweeps: the sweep file, the parallel resumable runner, its result and the crash-safe store.

Modules: :mod:`.spec` (the sweep file; its axes in :mod:`.axes`), :mod:`.runner` (processes or Dask;
its result in :mod:`.result`), :mod:`.store` (JSON Lines results).
"""
