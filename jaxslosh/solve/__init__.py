"""How the equations are solved in time: the schemes, one implicit step (Newton iterations with a
structured approximate inverse, implicit-function gradients), and the linear solvers of its
constant blocks."""
