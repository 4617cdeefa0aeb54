"""``gesticulator-original``: the original Gesticulator code (Kucherenko et al., ICMI 2020), run out of process.

The original (GPL-3, Python 3.6 / torch 1.4 / PyTorch Lightning 0.8.5) runs in the user's own environment
through the subprocess bridge; nothing of it is shipped or imported here. :mod:`.plugin` is the plug-in,
:mod:`.transcript` the Google ASR JSON conversion, ``driver.py`` the script that runs under the user's
interpreter.
"""
