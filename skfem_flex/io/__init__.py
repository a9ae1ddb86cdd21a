"""Files: the result and its archive, VTK series of the deformed system, plots, writes that survive a crash."""
