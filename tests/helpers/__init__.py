"""Helpers the tests share (imported as ``tests.helpers.X``): the CLI runner, run files, a scripted FRI client."""
