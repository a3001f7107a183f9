"""The faces' fixtures (tests/faces/conftest.py) where an adversarial test asks its question of
every face: ``face`` (the pythonfmu and native FMI 2.0 faces, the native FMI 3.0 face; a face
added there is asked here too) and ``face_fmus`` (its FMUs, built once per session)."""

from ..faces.conftest import face, face_fmus  # noqa: F401  (pytest finds fixtures by name)
