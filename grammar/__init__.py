"""Package data: the Lark grammar of cfgplan's language (installed as cfgplan.grammar)."""
