"""Scripted grasp strategies, one or more per environment."""
