"""Library workflows: what each command of the command line does, callable from Python."""
