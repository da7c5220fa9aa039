"""What Python tests and tools of more than one directory share (tests/support/python on sys.path):
`checks` (failing a test with a message) and `dds_domain` (a DDS domain no other running test
holds)."""
