"""Planning with learned affordances: forward model, goals, search, monitoring (imports learn and features; never sim)."""
