"""The checker's passes, in the order `Checker.run` applies them."""
