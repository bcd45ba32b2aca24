"""Text that reaches a terminal or a log."""
