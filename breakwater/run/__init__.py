"""One run: the time loop, its session of objects, how it begins and its state between steps."""
