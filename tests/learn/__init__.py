"""Tests of mmusv.learn (a package, so that test_decode.py here and tests/test_decode.py do not collide)."""
