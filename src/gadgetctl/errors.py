"""Errors that stop a command: usage and tool errors (exit code 2), never findings."""


class GadgetctlError(Exception):
    """A problem with the request or the environment, reported in one line with exit code 2."""

    exit_code = 2
