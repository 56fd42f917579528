"""What every algorithm shares, as SB3's ``common/``: the base classes and training loops,
buffers, policies and networks, callbacks, logger, schedules, model files and the
hyperparameter checks. Users import these modules by their public paths
(``palaestra.algos.callbacks``...; see ``palaestra.algos.public_paths``)."""
