"""Property-based tests and the fuzz campaign of every parser a hostile peer or file reaches.

``targets`` is the registry (one entry per parser or driver decoder), ``inputs`` the input
strategies (arbitrary bytes, grammar-made records, mutations of valid ones), ``campaign`` the
long run behind ``make fuzz``; ``test_fuzz`` gives every target a small budget in ``make test``.
"""
