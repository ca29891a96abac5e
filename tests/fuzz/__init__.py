"""Property-based tests and the fuzz campaign of every parser a hostile peer or file reaches.

``targets`` is the registry (one entry per parser or driver decoder), ``inputs`` the input
strategies (arbitrary bytes, grammar-made records, mutations of valid ones), ``campaign`` the
long run behind ``make fuzz``; ``test_fuzz`` gives every target a small budget in ``make test``.
``paths`` is the registry of the cross-layer targets (``path_vrpn``: serve and monitor vrpn:
against hostile VRPN peers; ``path_drivers``: UDP floods and pty streams through the input
manager), each with memory and time caps (``memory`` reads a process's resident memory);
``tests/test_fuzz_campaign.py`` runs each for a few seconds.
"""
