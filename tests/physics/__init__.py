"""Tests of graspenv.physics."""
