from armkit.cli import main

main()
