"""afford: learn what the world affords by playing in it (after Ugur's developmental framework)."""
