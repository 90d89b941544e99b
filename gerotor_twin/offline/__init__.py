"""Offline use of the twin without ROS: ``run_bag`` (the twin core over a recorded bag)."""
