"""The main job end to end, from speech to statistics: the steps of ``evalsuite demo``."""
