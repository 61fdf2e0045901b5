"""What was measured: tables of eigenvalues and canonical matrices, records and their repair, the
modes extracted from them, and the control laws the experiment ran."""
