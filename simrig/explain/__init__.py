"""What each cause of detector error cost a tracker: counterfactual reruns and Shapley shares
(:func:`explain`, ``simrig explain``)."""

from .api import ExplainError, ExplainResult, add_to_run_report, explain

__all__ = ["ExplainError", "ExplainResult", "add_to_run_report", "explain"]
