"""Parameter studies: a study file, its points run as cases, and their figures."""
