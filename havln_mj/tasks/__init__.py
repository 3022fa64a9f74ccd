"""Task layer: episodes, the task step, experts, metrics and the gym-free episode environment."""
