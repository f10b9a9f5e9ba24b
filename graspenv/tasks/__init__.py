"""Tasks: goals, rewards, success and grasp-stability metrics."""
