"""The shock methods, written once for every solver and driven through its protocol:
``piston`` (the piston driver), ``control`` (the ω signal, AMW and MW), ``dichotomy`` (its
loop state), ``steady`` (a window point's steady average), ``protocol`` (``ShockSolver``,
``WindowSolver``), and a front with an exact answer to test them on."""
