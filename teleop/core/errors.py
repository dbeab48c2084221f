"""Errors the command line turns into a one-line message and exit code 2."""


class InputError(ValueError):
    """Bad user input: a malformed file, key, column, argument or an impossible request.

    The message is one line naming the file (and line, key or column) and what was expected.
    """

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))


class InfeasibleError(InputError):
    """A request outside what the robot can do (unreachable pose, wrench outside the feasible set)."""
