"""One run: the time loop, its session of objects and its state between steps."""
