from softcell.cli import main

raise SystemExit(main())
