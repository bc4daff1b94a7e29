"""Measuring and fitting detector models: how a dataset's (or a user's) detector errs."""
