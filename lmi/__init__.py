"""LMI problem builders, solver back-ends and certificates for robust MPC."""
