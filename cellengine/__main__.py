from cellengine.cli import entry

entry()
