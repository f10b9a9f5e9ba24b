"""Baseline agents for graspenv: scripted strategies (``agents.scripted``), usable
wherever a stable-baselines3 model is (a ``predict`` method)."""
