"""The flexsat command called in process, as the command's tests call it."""
from spacecraft import cli

__all__ = ["flexsat"]


def flexsat(*args) -> int:
    """``flexsat ARGS...`` in this process (each argument as a string); its exit code."""
    return cli.main([str(a) for a in args])
