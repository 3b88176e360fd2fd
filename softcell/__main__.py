from softcell.cli import entry

entry()
