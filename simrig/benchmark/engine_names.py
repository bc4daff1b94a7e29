"""The engines a bench can run on (a module of its own so that the command line can list them cheaply)."""

ENGINES: tuple[str, ...] = ("local", "ray")
"""``local``: a process pool on this machine; ``ray``: Ray tasks (a local instance or a cluster)."""
