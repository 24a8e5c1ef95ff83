"""The checker's rules, one per module: each enforces one coherent check and raises its own
diagnostic code(s), named in its docstring (tests/test_architecture.py holds them to it).

The parts (declarations, expressions, calls, statements, test statements) walk and type the
program and call a rule where its question comes up, so the diagnostics keep their order; the
passes call the rules that need the whole program (recursion, self-containment, unused
variables, storage limits, overrides). Each rule has a failing fixture per code
(tests/fixtures/errors/) and a passing one (tests/fixtures/ok/<rule>.st).
"""
