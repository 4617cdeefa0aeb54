"""Objective metrics for speech-driven gesture generation, one plain function per metric.

Kinematics (:mod:`~evalsuite.metrics.kinematics`): :func:`average_speed`,
:func:`average_acceleration`, :func:`average_jerk`, :func:`derivative_norms`.
Histograms (:mod:`~evalsuite.metrics.histograms`): :func:`joint_histograms`,
:func:`hellinger_distance`, :func:`clipped_fraction`.
Errors against ground truth (:mod:`~evalsuite.metrics.pose_errors`):
:func:`average_position_error` (APE), :func:`mean_absolute_error` (MAE), :func:`align_lengths`.
Distribution distances (:mod:`~evalsuite.metrics.distribution`): :func:`fd_g`, :func:`fd_k`,
:func:`l1div`, :func:`div_k`; Fréchet distance (:mod:`~evalsuite.metrics.frechet`).
CCA (:mod:`~evalsuite.metrics.cca`): :func:`cca_fit`, :func:`cca_score`, :func:`canonical_correlation`.
Beat alignment (:mod:`~evalsuite.metrics.beats`): :func:`audio_onsets`, :func:`motion_beats`,
:func:`beat_alignment`. Conventions: :data:`CONVENTIONS`. Whole folders:
:func:`~evalsuite.metrics.engine.score_folders` (what ``evalsuite score`` runs) over the metric families
registered in :mod:`evalsuite.metrics.families` (add one with :func:`register_family`).

Positions are world positions ``(T, J, 3)`` in file units (``Motion.positions()``).
"""
from evalsuite.metrics.beats import (
                                     audio_onsets,
                                     beat_alignment,
                                     beat_alignment_score,
                                     motion_beats,
                                     onset_strength,
                                     read_wav,
)
from evalsuite.metrics.cca import CCAModel, canonical_correlation, cca_fit, cca_score
from evalsuite.metrics.conventions import CONVENTIONS, Convention, get_convention
from evalsuite.metrics.distribution import div_k, fd_g, fd_k, l1div
from evalsuite.metrics.families import MetricFamily, MetricInfo, register_family
from evalsuite.metrics.frechet import (
                                     FrechetWarning,
                                     frechet_distance,
                                     frechet_distance_details,
                                     frechet_distance_samples,
                                     gaussian_stats,
)
from evalsuite.metrics.histograms import clipped_fraction, hellinger_distance, joint_histograms
from evalsuite.metrics.kinematics import (
                                     across_sequences,
                                     average_acceleration,
                                     average_jerk,
                                     average_speed,
                                     derivative_norms,
                                     sequence_means,
)
from evalsuite.metrics.pose_errors import (
                                     LengthMismatchWarning,
                                     align_lengths,
                                     average_position_error,
                                     mean_absolute_error,
)

__all__ = [
    "audio_onsets", "beat_alignment", "beat_alignment_score", "motion_beats", "onset_strength", "read_wav",
    "CCAModel", "canonical_correlation", "cca_fit", "cca_score",
    "CONVENTIONS", "Convention", "get_convention",
    "div_k", "fd_g", "fd_k", "l1div",
    "FrechetWarning", "frechet_distance", "frechet_distance_details", "frechet_distance_samples", "gaussian_stats",
    "clipped_fraction", "hellinger_distance", "joint_histograms",
    "across_sequences", "average_acceleration", "average_jerk", "average_speed", "derivative_norms",
    "sequence_means",
    "LengthMismatchWarning", "align_lengths", "average_position_error", "mean_absolute_error",
    "MetricFamily", "MetricInfo", "register_family",
]
