"""swgsim."""
