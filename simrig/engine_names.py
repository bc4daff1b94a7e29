"""The engines simrig fans out on — a bench, a collection, an explanation, a search — (a module of its own so that
the command line can list them cheaply; :mod:`simrig.pools` runs them)."""

ENGINES: tuple[str, ...] = ("local", "ray")
"""``local``: a process pool on this machine; ``ray``: Ray tasks (a local instance or a cluster)."""
