"""A test backend with an exact answer: a steady shock in a material whose Hugoniot is the
line D = c0 + s u_p, solved by nothing (``model``); it runs through the same stages and
workflow as the real solvers."""
