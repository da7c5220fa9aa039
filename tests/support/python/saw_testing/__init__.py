"""What Python tests and tools of more than one directory share (tests/support/python on sys.path):
`dds_domain` (a DDS domain no other running test holds)."""
