"""The benchmark suite behind ``acdrive bench``: matched cases against motulator 0.18 and
gym-electric-motor 3.0.3 with both sides' accuracy, and the ICAD timing (``suite`` runs them;
``venvs`` makes the peers' virtualenvs; ``peers/`` holds the scripts run inside them)."""
