"""Running a scene: the compiled time loop, `simulate`, batches, and the command line's run to a file."""
