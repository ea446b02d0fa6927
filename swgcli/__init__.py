"""swgcli."""
