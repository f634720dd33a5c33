"""Robot models (SVH hand, UR10 arm) and the one place that adds them to a plant."""
