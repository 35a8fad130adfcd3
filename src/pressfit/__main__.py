from pressfit.cli import main

main()
