"""A third-party package as a user would write one: a logical scenario and a baseline, one file
each, registered through entry points only (tests/test_plugins.py installs its metadata)."""
