"""``upm studio``: an interactive transition studio in the browser (viser, three.js).

:mod:`studio.session` holds the state and the recomputation (no web code);
:mod:`studio.app` draws it with viser.
"""
