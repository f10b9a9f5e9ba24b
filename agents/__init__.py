"""Baseline agents for graspenv: scripted strategies, training, evaluation and
comparison, usable wherever a stable-baselines3 model is (a ``predict`` method).

The repository keeps them in the folder ``agents/``; they install as the package
``graspenv_agents`` (``pyproject.toml``), so that nothing lands in site-packages
under a generic name. Imports inside the package are relative: the installed code
runs as ``graspenv_agents`` while mypy checks the folder as ``agents`` (it does not
follow the editable install's import hook).
"""
