"""The hostile-user campaign's classes and helpers (scripts/hostile_campaign.py)."""
