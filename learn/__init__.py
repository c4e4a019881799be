"""Learning affordances: effect categories, relevant features, predictors (imports features only)."""
