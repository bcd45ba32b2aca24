"""Text that reaches a terminal or a log: escaping, line budgets, the terminal writer and fd 2."""
