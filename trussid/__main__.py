from trussid.cli import main

raise SystemExit(main())
