"""Flask server for crowd perceptual studies (pairwise, MUSHRA-style, Likert).

``create_app(config)`` is the application factory; ``evalsuite study ...`` drives it.
"""


def create_app(config):
    from study_app.app import create_app as _create_app
    return _create_app(config)


__all__ = ["create_app"]
