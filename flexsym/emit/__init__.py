"""Layer 3, emit: sympy expressions to casadi functions (CSE, AD Jacobians) and casadi's
instruction lists to C99. Knows no physics."""
